// The dig: where the scoop goes for each pass, which particles it holds, and the wrench on it in
// the frames the study and the lander simulator use (paper section 4, eqs. 2-3).
#pragma once

#include <vector>

#include "dem/mesh.h"
#include "dem/system.h"
#include "dem/transform.h"

namespace sim {

// Wrench of the particles on the scoop about its centre of mass, in three frames.
//   world: the simulation frame (x along the trench for heading 0, z up).
//   scoop: the l_scoop frame (the frame the lander simulator applies a wrench in).
//   body:  the study's body frame (paper Fig. 1): origin at the CoM, X parallel to the rotation
//          axis of the dig, Z opposite gravity, Y = Z x X. With the trench along world +x
//          (heading 0) and the scoop pitching about world y, X = -y_world and Y = +x_world: Y
//          points along the digging direction.
struct ScoopWrench {
  dem::Vec3 force_world, torque_world;  // [N], [N m] about the CoM
  dem::Vec3 force_scoop, torque_scoop;
  dem::Vec3 force_body, torque_body;
};

// Axes of the study's body frame in world coordinates for a dig along `heading` [rad] (rotation
// of the trench direction about world z from +x) under gravity `gravity`.
struct BodyFrame {
  dem::Vec3 x, y, z;
};
BodyFrame StudyBodyFrame(double heading, const dem::Vec3& gravity);

// From the mesh wrench of dem::System (force, torque about the mesh body origin = pose.position)
// to the three frames, about the CoM given in the l_scoop frame.
ScoopWrench ComputeScoopWrench(const dem::MeshWrench& wrench, const dem::Pose& pose,
                               const dem::Vec3& com_scoop, const BodyFrame& body);

// Height of the free surface of a bed [m]: the mean, over square columns of side `column` inside
// [lo, hi] (x, y), of the highest particle top (z + r) in each column; empty columns are skipped.
double BedSurface(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi, double column);

// The free surface of a bed as a height field (the local surface `scoopsim study balovnev` cuts
// below): top[cy * nx + cx] is the highest particle top (z + r) among the particles whose centres
// lie in square column (cx, cy) of side `column` from `lo` (x, y); -inf for an empty column.
struct SurfaceMap {
  dem::Vec3 lo;       // corner of column (0, 0) [m]
  double column = 0;  // side of a column [m]
  int nx = 0, ny = 0;
  std::vector<double> top;  // [m] (nx x ny)
  // The surface at (x, y) [m]: the mean of the non-empty columns among the 3 x 3 around the one
  // holding (x, y) (clamped to the grid), so one grain standing proud moves it by a ninth; NaN
  // when all nine are empty.
  double Height(double x, double y) const;
};
// Columns of side `column` > 0 over [lo, hi] (x, y), as many as fit (at least one each way).
SurfaceMap MeasureSurfaceMap(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi,
                             double column);

// Solid fraction of the bed in the box [lo, hi]: the volume of the spheres whose centres lie in it
// over the box's volume (spheres cut by the box's faces count whole, so keep the box a few
// diameters inside the bed). Clump spheres count whole: their overlaps are counted twice.
double SolidFraction(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi);

// Persistent ids of the particles whose centres lie inside the box [cavity_min, cavity_max] of
// the l_scoop frame at `pose`, and their total mass [kg]. With `clumps`, a clump counts by its
// centre of mass: all its spheres or none, and its mass once.
std::vector<int64_t> ParticlesInCavity(const dem::Particles& p, const dem::Pose& pose,
                                       const dem::Vec3& cavity_min, const dem::Vec3& cavity_max,
                                       double* mass, const dem::Clumps* clumps = nullptr);

// Persistent ids of the particles that overlap the mesh at `pose` (centre closer than its radius
// to a triangle), sorted.
std::vector<int64_t> ParticlesTouchingMesh(const dem::Particles& p, const dem::TriangleMesh& mesh,
                                           const dem::Pose& pose);

// Persistent ids of the particles that overlap the sphere (centre, radius), sorted.
std::vector<int64_t> ParticlesInSphere(const dem::Particles& p, const dem::Vec3& center,
                                       double radius);

// A sphere of `radius` about the body origin as a closed triangle mesh: an icosahedron split
// `subdivisions` times (20 x 4^s faces; 2: 320 faces, within 2% of the radius).
dem::TriangleMesh SphereMesh(double radius, int material, int subdivisions = 2);

// Lowest point of the mesh along world z, relative to the pivot, when the scoop is level
// (orientation `level`), with the pivot at `pivot_scoop` in the l_scoop frame [m] (negative).
double LowestBelowPivot(const dem::TriangleMesh& mesh, const dem::Quat& level,
                        const dem::Vec3& pivot_scoop);

}  // namespace sim

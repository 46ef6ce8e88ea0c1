// Triangle-mesh walls (the scoop): geometry in the mesh's own body frame, moved kinematically by
// the caller every step (pose + twist). Public header of the dem module.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "dem/transform.h"
#include "dem/vec3.h"

namespace dem {

struct TriangleMesh {
  std::string name;
  std::vector<Vec3> vertices;                     // [m] in the body frame (V)
  std::vector<std::array<int32_t, 3>> triangles;  // vertex indices, counter-clockwise seen from
                                                  // outside (T)
  int material = 0;                               // index into the MaterialTable
};

// Kinematic state of a mesh: pose of its body frame and the velocity of that frame's origin.
struct MeshMotion {
  Pose pose;
  Vec3 velocity;          // of the body origin [m/s], world frame
  Vec3 angular_velocity;  // [rad/s], world frame
};

// Mass properties of the solid a closed triangle mesh bounds, at uniform density.
struct MassProperties {
  double volume = 0;    // [m^3]
  double mass = 0;      // [kg] density * volume
  Vec3 center_of_mass;  // [m] in the mesh's body frame
  // Inertia tensor about the centre of mass, body axes [kg m^2]: I_ij = integral of
  // (|r|^2 delta_ij - r_i r_j) dm, so the off-diagonal entries are the negated products of
  // inertia (the URDF ixy, ixz, iyz convention). Symmetric.
  std::array<std::array<double, 3>, 3> inertia{};
};

// Volume, mass, centre of mass and inertia of `mesh` at `density` [kg/m^3], exactly (up to
// rounding) by the divergence theorem over its triangles: each volume integral of 1, x, y, z,
// x^2, y^2, z^2, xy, yz, zx becomes a sum over the surface (Mirtich 1996; Eberly, "Polyhedral
// Mass Properties (Revisited)", 2002). Coordinates are taken relative to the mean vertex first,
// so a mesh far from its origin loses no digits.
// Hazards: the mesh must be closed, with triangles counter-clockwise seen from outside; an open
// mesh gives a meaningless answer. For a union of closed pieces that intersect (the scoop's
// plates overlap at the joints), every overlap is counted once per piece that covers it.
// Throws MeshError when density is not > 0 (field "density"), a vertex index is out of range
// ("triangles") or the enclosed volume is not > 0 ("volume": an empty or open mesh, or one wound
// inside out).
MassProperties ComputeMassProperties(const TriangleMesh& mesh, double density);

// A mesh, or an argument, that a computation on it refuses, as data in dem's own terms: `field`
// names what is wrong ("density", "triangles", "volume"), `expected` and `got` say how (SI). A
// caller reporting a user's file maps the field onto its own key. what() is one line naming the
// mesh: "mesh 'NAME': FIELD: expected EXPECTED, got GOT".
class MeshError : public std::invalid_argument {
 public:
  MeshError(const std::string& mesh, std::string field, std::string expected, std::string got);
  const std::string& field() const { return field_; }
  const std::string& expected() const { return expected_; }
  const std::string& got() const { return got_; }

 private:
  std::string field_, expected_, got_;
};

}  // namespace dem

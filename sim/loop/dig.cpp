#include "sim/loop/dig.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "dem/triangle.h"

namespace sim {

BodyFrame StudyBodyFrame(double heading, const dem::Vec3& gravity) {
  BodyFrame b;
  const double gn = dem::Norm(gravity);
  b.z = gn > 0 ? (-1.0 / gn) * gravity : dem::Vec3{0, 0, 1};
  // The pitch axis of a dig along heading h is the horizontal direction across the trench;
  // X is its negative so that Y = Z x X points forward along the trench.
  const dem::Vec3 across{-std::sin(heading), std::cos(heading), 0.0};  // world y at heading 0
  dem::Vec3 x = -1.0 * across;
  x = x - dem::Dot(x, b.z) * b.z;  // horizontal for a tilted gravity too
  b.x = (1.0 / dem::Norm(x)) * x;
  b.y = dem::Cross(b.z, b.x);
  return b;
}

ScoopWrench ComputeScoopWrench(const dem::MeshWrench& wrench, const dem::Pose& pose,
                               const dem::Vec3& com_scoop, const BodyFrame& body) {
  ScoopWrench w;
  // Paper eqs. 2-3: F = sum F_i, T = sum r_i x F_i with r_i from the CoM. dem gives the moment
  // about the mesh body origin O; about the CoM C it is T_O - (C - O) x F.
  const dem::Vec3 arm = dem::Rotate(pose.orientation, com_scoop);  // C - O
  w.force_world = wrench.force;
  w.torque_world = wrench.torque - dem::Cross(arm, wrench.force);
  w.force_scoop = dem::RotateInverse(pose.orientation, w.force_world);
  w.torque_scoop = dem::RotateInverse(pose.orientation, w.torque_world);
  auto to_body = [&](const dem::Vec3& v) {
    return dem::Vec3{dem::Dot(v, body.x), dem::Dot(v, body.y), dem::Dot(v, body.z)};
  };
  w.force_body = to_body(w.force_world);
  w.torque_body = to_body(w.torque_world);
  return w;
}

double BedSurface(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi,
                  double column) {
  const int nx = std::max(1, static_cast<int>((hi.x - lo.x) / column));
  const int ny = std::max(1, static_cast<int>((hi.y - lo.y) / column));
  std::vector<double> top(static_cast<size_t>(nx) * ny, -1e300);
  for (size_t i = 0; i < p.size(); ++i) {
    const dem::Vec3& x = p.x[i];
    if (x.x < lo.x || x.x >= hi.x || x.y < lo.y || x.y >= hi.y) continue;
    const int cx = std::min(nx - 1, static_cast<int>((x.x - lo.x) / (hi.x - lo.x) * nx));
    const int cy = std::min(ny - 1, static_cast<int>((x.y - lo.y) / (hi.y - lo.y) * ny));
    double& t = top[static_cast<size_t>(cy) * nx + cx];
    t = std::max(t, x.z + p.radius[i]);
  }
  double sum = 0;
  int count = 0;
  for (double t : top)
    if (t > -1e300) {
      sum += t;
      ++count;
    }
  return count > 0 ? sum / count : lo.z;
}

SurfaceMap MeasureSurfaceMap(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi,
                             double column) {
  SurfaceMap m;
  m.lo = lo;
  m.column = column;
  m.nx = std::max(1, static_cast<int>((hi.x - lo.x) / column));
  m.ny = std::max(1, static_cast<int>((hi.y - lo.y) / column));
  m.top.assign(static_cast<size_t>(m.nx) * m.ny, -std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < p.size(); ++i) {
    const dem::Vec3& x = p.x[i];
    const int cx = static_cast<int>(std::floor((x.x - lo.x) / column));
    const int cy = static_cast<int>(std::floor((x.y - lo.y) / column));
    if (cx < 0 || cx >= m.nx || cy < 0 || cy >= m.ny) continue;
    double& t = m.top[static_cast<size_t>(cy) * m.nx + cx];
    t = std::max(t, x.z + p.radius[i]);
  }
  return m;
}

double SurfaceMap::Height(double x, double y) const {
  const int cx = std::clamp(static_cast<int>(std::floor((x - lo.x) / column)), 0, nx - 1);
  const int cy = std::clamp(static_cast<int>(std::floor((y - lo.y) / column)), 0, ny - 1);
  double sum = 0;
  int count = 0;
  for (int j = std::max(0, cy - 1); j <= std::min(ny - 1, cy + 1); ++j)
    for (int i = std::max(0, cx - 1); i <= std::min(nx - 1, cx + 1); ++i) {
      const double t = top[static_cast<size_t>(j) * nx + i];
      if (std::isfinite(t)) {
        sum += t;
        ++count;
      }
    }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

double SolidFraction(const dem::Particles& p, const dem::Vec3& lo, const dem::Vec3& hi) {
  double solid = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const dem::Vec3& x = p.x[i];
    if (x.x < lo.x || x.x >= hi.x || x.y < lo.y || x.y >= hi.y || x.z < lo.z || x.z >= hi.z)
      continue;
    const double r = p.radius[i];
    solid += 4.0 / 3.0 * M_PI * r * r * r;
  }
  return solid / ((hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z));
}

std::vector<int64_t> ParticlesInCavity(const dem::Particles& p, const dem::Pose& pose,
                                       const dem::Vec3& cavity_min, const dem::Vec3& cavity_max,
                                       double* mass, const dem::Clumps* clumps) {
  auto inside = [&](const dem::Vec3& x) {
    const dem::Vec3 b = dem::ApplyInverse(pose, x);
    return b.x >= cavity_min.x && b.x <= cavity_max.x && b.y >= cavity_min.y &&
           b.y <= cavity_max.y && b.z >= cavity_min.z && b.z <= cavity_max.z;
  };
  std::vector<int64_t> ids;
  std::vector<int64_t> members;  // spheres of clumps, sorted: judged with their clump
  if (clumps) members = clumps->member;
  std::sort(members.begin(), members.end());
  double m = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (std::binary_search(members.begin(), members.end(), p.id[i])) continue;
    if (inside(p.x[i])) {
      ids.push_back(p.id[i]);
      m += p.mass[i];
    }
  }
  for (size_t c = 0; clumps && c < clumps->size(); ++c) {
    if (!inside(clumps->x[c])) continue;
    ids.insert(ids.end(), clumps->member.begin() + clumps->first[c],
               clumps->member.begin() + clumps->first[c + 1]);
    m += clumps->mass[c];
  }
  std::sort(ids.begin(), ids.end());
  if (mass) *mass = m;
  return ids;
}

std::vector<int64_t> ParticlesTouchingMesh(const dem::Particles& p, const dem::TriangleMesh& mesh,
                                           const dem::Pose& pose) {
  std::vector<dem::Vec3> world;
  for (const dem::Vec3& v : mesh.vertices) world.push_back(dem::Apply(pose, v));
  std::vector<int64_t> ids;
  for (size_t i = 0; i < p.size(); ++i) {
    const double r = p.radius[i];
    for (const auto& t : mesh.triangles) {
      const dem::ClosestPoint cp =
          dem::ClosestPointOnTriangle(p.x[i], world[t[0]], world[t[1]], world[t[2]]);
      if (dem::Norm2(p.x[i] - cp.point) < r * r) {
        ids.push_back(p.id[i]);
        break;
      }
    }
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

std::vector<int64_t> ParticlesInSphere(const dem::Particles& p, const dem::Vec3& center,
                                       double radius) {
  std::vector<int64_t> ids;
  for (size_t i = 0; i < p.size(); ++i) {
    const double reach = radius + p.radius[i];
    if (dem::Norm2(p.x[i] - center) < reach * reach) ids.push_back(p.id[i]);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

dem::TriangleMesh SphereMesh(double radius, int material, int subdivisions) {
  // Icosahedron (vertices on the three golden rectangles), each face split in four per level,
  // new vertices pushed out onto the sphere; faces counter-clockwise seen from outside.
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<dem::Vec3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                              {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                              {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<int32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (dem::Vec3& x : v) x = (1.0 / dem::Norm(x)) * x;
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int32_t, int32_t>, int32_t> middle;
    auto mid = [&](int32_t a, int32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      const dem::Vec3 m = v[a] + v[b];
      v.push_back((1.0 / dem::Norm(m)) * m);
      return middle[key] = static_cast<int32_t>(v.size() - 1);
    };
    std::vector<std::array<int32_t, 3>> next;
    for (const auto& t : f) {
      const int32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  dem::TriangleMesh mesh;
  mesh.name = "obstacle";
  for (const dem::Vec3& x : v) mesh.vertices.push_back(radius * x);
  mesh.triangles = std::move(f);
  mesh.material = material;
  return mesh;
}

double LowestBelowPivot(const dem::TriangleMesh& mesh, const dem::Quat& level,
                        const dem::Vec3& pivot_scoop) {
  double lowest = 1e300;
  for (const dem::Vec3& v : mesh.vertices)
    lowest = std::min(lowest, dem::Rotate(level, v - pivot_scoop).z);
  return lowest;
}

}  // namespace sim

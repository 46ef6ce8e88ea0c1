// Mass properties of closed triangle meshes against closed forms (dem/mesh.cpp).
#include "dem/mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace dem {
namespace {

// A closed box of edge lengths (a, b, c) centred on the origin of its own frame, placed at `pose`:
// 8 vertices, 12 triangles counter-clockwise seen from outside.
TriangleMesh BoxMesh(double a, double b, double c, const Pose& pose) {
  TriangleMesh m;
  m.name = "box";
  for (int k = 0; k < 8; ++k) {  // corner k = 4 (z > 0) + 2 (y > 0) + (x > 0)
    const Vec3 local{(k & 1 ? 0.5 : -0.5) * a, (k & 2 ? 0.5 : -0.5) * b, (k & 4 ? 0.5 : -0.5) * c};
    m.vertices.push_back(Apply(pose, local));
  }
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

// Closed form for a solid box about its centre, body axes: diag(m(b^2+c^2)/12, m(c^2+a^2)/12,
// m(a^2+b^2)/12), turned to the world axes: I = R D R^T.
std::array<std::array<double, 3>, 3> BoxInertia(double a, double b, double c, double mass,
                                                const Quat& q) {
  const double d[3] = {mass * (b * b + c * c) / 12, mass * (c * c + a * a) / 12,
                       mass * (a * a + b * b) / 12};
  const Vec3 col[3] = {Rotate(q, {1, 0, 0}), Rotate(q, {0, 1, 0}), Rotate(q, {0, 0, 1})};
  std::array<std::array<double, 3>, 3> out{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) out[i][j] += col[k][i] * d[k] * col[k][j];
    }
  }
  return out;
}

// Every entry within `rel` of the largest entry of `expected`.
void ExpectInertiaNear(const std::array<std::array<double, 3>, 3>& got,
                       const std::array<std::array<double, 3>, 3>& expected, double rel) {
  double largest = 0;
  for (const auto& row : expected) {
    for (double v : row) largest = std::max(largest, std::abs(v));
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(got[i][j], expected[i][j], rel * largest) << "entry " << i << j;
    }
  }
}

constexpr double kRel = 1e-12;

// Unit cube [0,1]^3 at density 1: V = 1, CoM (1/2, 1/2, 1/2), I = diag(1/6), no products.
TEST(MassPropertiesTest, UnitCube) {
  const TriangleMesh cube = BoxMesh(1, 1, 1, Pose{{0.5, 0.5, 0.5}, {}});
  const MassProperties mp = ComputeMassProperties(cube, 1.0);
  EXPECT_NEAR(mp.volume, 1.0, kRel);
  EXPECT_NEAR(mp.mass, 1.0, kRel);
  EXPECT_NEAR(mp.center_of_mass.x, 0.5, kRel);
  EXPECT_NEAR(mp.center_of_mass.y, 0.5, kRel);
  EXPECT_NEAR(mp.center_of_mass.z, 0.5, kRel);
  ExpectInertiaNear(mp.inertia, {{{1.0 / 6, 0, 0}, {0, 1.0 / 6, 0}, {0, 0, 1.0 / 6}}}, kRel);
}

// An axis-aligned plate like the scoop's bottom (0.1273 x 0.0818 x 0.002 m, aluminium 2700
// kg/m^3): Ixx = m(b^2+c^2)/12, Iyy = m(c^2+a^2)/12, Izz = m(a^2+b^2)/12.
TEST(MassPropertiesTest, AxisAlignedBoxMatchesClosedForm) {
  const double a = 0.1273, b = 0.0818, c = 0.002, rho = 2700;
  const Pose pose{{0.030115, 0, 0.076505}, {}};
  const MassProperties mp = ComputeMassProperties(BoxMesh(a, b, c, pose), rho);
  const double m = rho * a * b * c;
  EXPECT_NEAR(mp.volume, a * b * c, kRel * a * b * c);
  EXPECT_NEAR(mp.mass, m, kRel * m);
  EXPECT_NEAR(mp.center_of_mass.x, pose.position.x, kRel * a);
  EXPECT_NEAR(mp.center_of_mass.y, pose.position.y, kRel * a);
  EXPECT_NEAR(mp.center_of_mass.z, pose.position.z, kRel * a);
  EXPECT_NEAR(mp.inertia[0][0], m * (b * b + c * c) / 12, kRel * mp.inertia[0][0]);
  EXPECT_NEAR(mp.inertia[1][1], m * (c * c + a * a) / 12, kRel * mp.inertia[1][1]);
  EXPECT_NEAR(mp.inertia[2][2], m * (a * a + b * b) / 12, kRel * mp.inertia[2][2]);
  ExpectInertiaNear(mp.inertia, BoxInertia(a, b, c, m, Quat{}), kRel);
}

// A rotated, translated box far from the origin: volume abc, CoM at the translation,
// inertia R diag(...) R^T about the CoM.
TEST(MassPropertiesTest, RotatedTranslatedBoxMatchesClosedForm) {
  const double a = 0.3, b = 0.2, c = 0.1, rho = 917;
  const Vec3 axis = (1.0 / std::sqrt(14.0)) * Vec3{1, 2, 3};
  const Pose pose{{1.5, -2.25, 0.75}, AxisAngle(axis, 0.7)};
  const MassProperties mp = ComputeMassProperties(BoxMesh(a, b, c, pose), rho);
  const double m = rho * a * b * c;
  EXPECT_NEAR(mp.volume, a * b * c, kRel * a * b * c);
  EXPECT_NEAR(mp.mass, m, kRel * m);
  // The box corners carry the rounding of the rotation (~1e-16 m at 2 m from the origin).
  EXPECT_NEAR(mp.center_of_mass.x, pose.position.x, kRel * 2);
  EXPECT_NEAR(mp.center_of_mass.y, pose.position.y, kRel * 2);
  EXPECT_NEAR(mp.center_of_mass.z, pose.position.z, kRel * 2);
  ExpectInertiaNear(mp.inertia, BoxInertia(a, b, c, m, pose.orientation), kRel);
  EXPECT_DOUBLE_EQ(mp.inertia[0][1], mp.inertia[1][0]);
  EXPECT_DOUBLE_EQ(mp.inertia[0][2], mp.inertia[2][0]);
  EXPECT_DOUBLE_EQ(mp.inertia[1][2], mp.inertia[2][1]);
}

// Two intersecting boxes in one mesh: the overlap is counted twice (documented hazard).
TEST(MassPropertiesTest, IntersectingBoxesCountTheOverlapTwice) {
  TriangleMesh m = BoxMesh(1, 1, 1, Pose{{0, 0, 0}, {}});
  const TriangleMesh second = BoxMesh(1, 1, 1, Pose{{0.5, 0, 0}, {}});
  const int32_t base = static_cast<int32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), second.vertices.begin(), second.vertices.end());
  for (const auto& t : second.triangles)
    m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const MassProperties mp = ComputeMassProperties(m, 1.0);
  EXPECT_NEAR(mp.volume, 2.0, kRel);  // the union is 1.5
  EXPECT_NEAR(mp.center_of_mass.x, 0.25, kRel);
}

TEST(MassPropertiesTest, BadInputThrows) {
  TriangleMesh box = BoxMesh(1, 2, 3, Pose{});
  EXPECT_THROW(ComputeMassProperties(box, 0.0), std::invalid_argument);
  EXPECT_THROW(ComputeMassProperties(box, NAN), std::invalid_argument);
  EXPECT_THROW(ComputeMassProperties(TriangleMesh{}, 1.0), std::invalid_argument);
  TriangleMesh inside_out = box;
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(ComputeMassProperties(inside_out, 1.0), std::invalid_argument);
  TriangleMesh bad_index = box;
  bad_index.triangles[3][1] = 8;
  EXPECT_THROW(ComputeMassProperties(bad_index, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace dem

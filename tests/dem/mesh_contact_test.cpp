// Sphere-triangle-mesh contacts against closed forms: a sphere resting and rolling on a flat
// floor made of many triangles carries exactly its weight (no double counting on shared edges
// and vertices), and impacts on a mesh face, edge and vertex rebound with the restitution.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "dem/triangle.h"
#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;  // 3.5 mm snow sphere [m]

SystemConfig Config(const Vec3& gravity, double rayleigh_fraction = 0.1) {
  SystemConfig c;
  c.gravity = gravity;
  c.time_step = rayleigh_fraction * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  c.domain_min = Vec3{-0.05, -0.05, -0.05};
  c.domain_max = Vec3{0.05, 0.05, 0.05};
  c.max_speed = 10.0;
  return c;
}

// A flat square floor z = 0 of side `size` centred on the origin, cut into cells x cells squares
// of two triangles each; the diagonals alternate so vertices join 4 or 8 triangles.
// `shift` is added to every vertex (the body frame then sits at -shift from the floor centre).
TriangleMesh GridFloor(double size, int cells, int material, const Vec3& shift = {}) {
  TriangleMesh m;
  m.material = material;
  const double h = size / cells;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      m.vertices.push_back(Vec3{-0.5 * size + i * h, -0.5 * size + j * h, 0} + shift);
  auto id = [&](int i, int j) { return static_cast<int32_t>(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const int32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      } else {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({b, c, d});
      }
    }
  return m;
}

MeshMotion AtRest(const Vec3& position = {}) {
  MeshMotion mm;
  mm.pose.position = position;
  return mm;
}

TEST(TriangleTest, ClosestPointRegions) {
  // Closed form: projections onto the plane, the edge lines and the vertices of a right triangle.
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  auto check = [&](Vec3 p, Vec3 expected, TriangleRegion region) {
    const ClosestPoint cp = ClosestPointOnTriangle(p, a, b, c);
    EXPECT_NEAR(Norm(cp.point - expected), 0.0, 1e-15);
    EXPECT_EQ(cp.region, region);
  };
  check({0.2, 0.2, 3}, {0.2, 0.2, 0}, TriangleRegion::kFace);
  check({0.5, -1, 1}, {0.5, 0, 0}, TriangleRegion::kEdgeAB);
  check({-1, 0.5, 0}, {0, 0.5, 0}, TriangleRegion::kEdgeCA);
  check({1, 1, -2}, {0.5, 0.5, 0}, TriangleRegion::kEdgeBC);
  check({-1, -1, 0}, a, TriangleRegion::kVertexA);
  check({2, -0.1, 0}, b, TriangleRegion::kVertexB);
  check({-0.1, 2, 0}, c, TriangleRegion::kVertexC);
}

// A sphere at rest on a floor of 800 triangles: the mesh carries m g (0.5%) and the torque about
// a reference point P is (x_contact - P) x F (0.5%); one contact only.
TEST(MeshContactTest, RestingSphereCarriesItsWeight) {
  const Vec3 g{0, 0, -9.81};
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), Config(g));
  s.set_num_threads(1);
  // The torque reference is the mesh body origin, placed off the floor at `ref`.
  const Vec3 ref{0.004, -0.007, 0.03};
  const int floor = s.AddMesh(GridFloor(0.04, 20, 1, -ref));
  s.SetMeshMotion(floor, AtRest(ref));
  // On a vertex shared by 8 triangles (grid point (0.002 * 10, ...) = origin), slightly above.
  s.AddParticle({0, 0, kRadius * 1.001}, {}, {}, kRadius, 0);
  test::StepOk(s, 20000);
  const double weight = s.particles().mass[0] * 9.81;
  const MeshWrench w = s.mesh_wrench(floor);
  EXPECT_EQ(w.contacts, 1);
  EXPECT_NEAR(w.force.z, -weight, 5e-3 * weight);
  EXPECT_NEAR(std::hypot(w.force.x, w.force.y), 0.0, 5e-3 * weight);
  const Vec3 xc{s.particles().x[0].x, s.particles().x[0].y, 0.0};
  const Vec3 expected = Cross(xc - ref, Vec3{0, 0, -weight});
  EXPECT_NEAR(Norm(w.torque - expected), 0.0, 5e-3 * Norm(expected));
}

// A sphere rolling across the triangulated floor (diagonal path over edges and 8-triangle
// vertices): at every step there is one contact and the normal force equals m g within 0.5%
// (no vertical acceleration while it rolls on a flat floor; a doubled contact would give 2 m g).
TEST(MeshContactTest, RollingAcrossEdgesAndVerticesNeverDoubles) {
  const Vec3 g{0, 0, -9.81};
  System s(test::SnowAndSteel({0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}), Config(g));
  s.set_num_threads(1);
  const int floor = s.AddMesh(GridFloor(0.04, 20, 1));
  s.SetMeshMotion(floor, AtRest());
  s.AddParticle({-0.015, -0.015, kRadius * 0.9999}, {}, {}, kRadius, 0);
  test::StepOk(s, 5000);  // settle onto the floor
  // Roll along the diagonal through the grid vertices at 0.05 m/s (v = w r).
  Particles& p = s.mutable_particles();
  const double v = 0.05 / std::sqrt(2.0);
  p.v[0] = {v, v, 0};
  p.w[0] = {-v / kRadius, v / kRadius, 0};
  const double weight = p.mass[0] * 9.81;
  int64_t steps = 0;
  while (s.particles().x[0].x < 0.015) {
    test::StepOk(s);
    const MeshWrench w = s.mesh_wrench(floor);
    ASSERT_EQ(w.contacts, 1) << "at x = " << s.particles().x[0].x;
    ASSERT_NEAR(-w.force.z, weight, 5e-3 * weight) << "at x = " << s.particles().x[0].x;
    ++steps;
  }
  EXPECT_GT(steps, 1000);  // it really travelled across ~21 vertices
}

// Restitution against a mesh: a sphere thrown at a cube's face, edge and vertex along the local
// normal (face normal, edge bisector, corner diagonal) rebounds with v_out / v_in = e within 1%,
// as it does from a plane (no gravity; the mesh is fixed; the exact_restitution damping law).
class MeshRestitutionTest : public ::testing::TestWithParam<std::tuple<int, double>> {};

TEST_P(MeshRestitutionTest, FaceEdgeVertex) {
  const auto [feature, e] = GetParam();
  const Interaction in{e, 0.5, 0.05, RollingModel::kEdem, DampingLaw::kExactRestitution};
  System s(test::SnowAndSteel(in, in), Config({0, 0, 0}));
  s.set_num_threads(1);
  const double h = 0.005;
  const int cube = s.AddMesh(test::Cube(h, 1));
  s.SetMeshMotion(cube, AtRest());
  // Direction of approach: towards the face centre, edge midpoint, or corner.
  Vec3 dir = feature == 0 ? Vec3{0, 0, 1} : feature == 1 ? Vec3{0, 1, 1} : Vec3{1, 1, 1};
  dir = (1.0 / Norm(dir)) * dir;
  const Vec3 target = feature == 0 ? Vec3{0, 0, h} : feature == 1 ? Vec3{0, h, h} : Vec3{h, h, h};
  const double speed = 0.1;
  s.AddParticle(target + (kRadius + 2e-5) * dir, -speed * dir, {}, kRadius, 0);
  for (int k = 0; k < 200000; ++k) {
    test::StepOk(s);
    if (Dot(s.particles().x[0] - target, dir) > kRadius + 1e-4) break;
  }
  const double v_out = Dot(s.particles().v[0], dir);
  EXPECT_NEAR(v_out / speed, e, 0.01 * e) << "feature " << feature;
}

INSTANTIATE_TEST_SUITE_P(Features, MeshRestitutionTest,
                         ::testing::Combine(::testing::Values(0, 1, 2),
                                            ::testing::Values(0.5, 0.88)));

// A moving mesh drags its contacts: a sphere resting on a floor that starts moving sideways at
// speed u ends up rolling on it. Angular momentum about the contact point is conserved (friction
// acts there), 0 = m v r - I w with rolling v - u = -w r, so v = 2/7 u (solid sphere,
// I = 2/5 m r^2); checked within 1% (no rolling resistance).
TEST(MeshContactTest, MovingFloorCarriesSphere) {
  const Vec3 g{0, 0, -9.81};
  System s(test::SnowAndSteel({0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}), Config(g));
  s.set_num_threads(1);
  const int floor = s.AddMesh(GridFloor(0.04, 4, 1));
  s.AddParticle({0, 0, kRadius * 0.9999}, {}, {}, kRadius, 0);
  MeshMotion mm = AtRest();
  s.SetMeshMotion(floor, mm);
  test::StepOk(s, 3000);
  const double u = 0.02;
  const double dt = s.config().time_step;
  for (int k = 0; k < 40000; ++k) {
    mm.pose.position.x = u * (k + 1) * dt;
    mm.velocity = {u, 0, 0};
    s.SetMeshMotion(floor, mm);
    test::StepOk(s);
  }
  EXPECT_NEAR(s.particles().v[0].x, 2.0 / 7.0 * u, 0.01 * 2.0 / 7.0 * u);
}

// Step(motion): the mesh's motion set from inside the step (where a coupled arm's step runs,
// beside the pair forces) gives the same bits as setting it before the step, on 1 and 2 threads,
// and the callback runs once a step. A pile of 48 spheres on a floor mesh that slides and tilts.
TEST(MeshContactTest, MotionSetInsideTheStepEqualsMotionSetBefore) {
  auto run = [](int threads, bool inside, int* calls) {
    System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), Config({0, 0, -9.81}));
    s.set_num_threads(threads);
    const int floor = s.AddMesh(GridFloor(0.04, 8, 1));
    s.SetMeshMotion(floor, AtRest());
    for (int k = 0; k < 48; ++k) {
      const Vec3 x{(k % 4 - 1.5) * 2.2 * kRadius + 1e-4 * (k % 3),
                   (k / 4 % 4 - 1.5) * 2.2 * kRadius, (1.01 + 2.02 * (k / 16)) * kRadius};
      s.AddParticle(x, {}, {}, kRadius, 0);
    }
    const double dt = s.config().time_step;
    for (int k = 0; k < 3000; ++k) {
      MeshMotion mm;
      const double t = (k + 1) * dt, angle = 10.0 * t;  // 10 rad/s about y
      mm.pose.position = {0.5 * t, 0, 0};
      mm.pose.orientation = {std::cos(0.5 * angle), 0, std::sin(0.5 * angle), 0};
      mm.velocity = {0.5, 0, 0};
      mm.angular_velocity = {0, 10.0, 0};
      StepStatus st;
      if (inside) {
        st = s.Step([&] {
          s.SetMeshMotion(floor, mm);
          ++*calls;
        });
      } else {
        s.SetMeshMotion(floor, mm);
        st = s.Step();
      }
      if (!st.ok()) {
        ADD_FAILURE() << st.message;
        return std::vector<double>{};
      }
    }
    EXPECT_GT(s.mesh_wrench(floor).contacts, 0);
    std::vector<double> out;
    for (size_t i = 0; i < s.particles().size(); ++i) {
      const Vec3 &x = s.particles().x[i], &v = s.particles().v[i];
      out.insert(out.end(),
                 {static_cast<double>(s.particles().id[i]), x.x, x.y, x.z, v.x, v.y, v.z});
    }
    const MeshWrench w = s.mesh_wrench(floor);
    out.insert(out.end(), {w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z});
    return out;
  };
  int calls = 0;
  const std::vector<double> before = run(1, false, &calls);
  for (int threads : {1, 2}) {
    calls = 0;
    EXPECT_EQ(run(threads, true, &calls), before) << threads << " threads";
    EXPECT_EQ(calls, 3000);
  }
}

}  // namespace
}  // namespace dem

// The three rolling-friction models of dem/contact.h (edem, cdt, legacy) against closed forms, on
// each kind of contact: particle-plane (EvaluateWallContact), particle-mesh (the same, through
// the mesh pass), and particle-particle (the batched kernel, with one material pair and with
// mixed pairs). Spheres of radius r, mass m, I = 2/5 m r^2; mu_r = 0.05, g = 1.3 m/s^2.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "dem/contact.h"
#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;  // [m]
constexpr double kMuR = 0.05;
constexpr double kG = 1.3;  // [m/s^2]

// A snow/steel table whose pairs all roll by `model` (exact restitution, friction 0.58).
MaterialTable Table(RollingModel model) {
  const Interaction i{0.5, 0.58, kMuR, model, DampingLaw::kExactRestitution};
  return test::SnowAndSteel(i, i);
}

SystemConfig Config(double gravity) {
  SystemConfig c;
  c.gravity = Vec3{0, 0, -gravity};
  c.time_step = 0.2 * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  c.domain_min = Vec3{-0.02, -0.02, -0.02};
  c.domain_max = Vec3{0.05, 0.02, 0.02};
  c.max_speed = 10.0;
  return c;
}

double Mass() { return test::Snow().density * 4.0 / 3.0 * M_PI * std::pow(kRadius, 3); }
double Inertia() { return 0.4 * Mass() * kRadius * kRadius; }

// The static Hertz overlap of a snow sphere carrying its weight on a steel floor.
double RestingOverlap() {
  const PairConstants pc = MakePairConstants(test::Snow(), test::Steel(), {});
  return std::pow(Mass() * kG / (4.0 / 3.0 * pc.e_star * std::sqrt(kRadius)), 2.0 / 3);
}

// The floor as a plane or as a triangle mesh (two triangles, z = 0).
enum class Floor { kPlane, kMesh };

std::unique_ptr<System> FloorSystem(RollingModel model, Floor floor,
                                    bool mesh_rolling_torque = false) {
  SystemConfig c = Config(kG);
  c.mesh_rolling_torque = mesh_rolling_torque;
  if (floor == Floor::kPlane) c.planes.push_back(test::Floor(0.0, 1));
  auto s = std::make_unique<System>(Table(model), c);
  s->set_num_threads(1);
  if (floor == Floor::kMesh) {
    TriangleMesh m;
    m.material = 1;
    m.vertices = {{-0.02, -0.02, 0}, {0.05, -0.02, 0}, {0.05, 0.02, 0}, {-0.02, 0.02, 0}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    const int k = s->AddMesh(m);
    MeshMotion at_rest;
    s->SetMeshMotion(k, at_rest);
  }
  return s;
}

class FloorRollingTest : public ::testing::TestWithParam<std::tuple<RollingModel, Floor>> {};

// Pure twist: a sphere resting on the floor, spun about the contact normal at w0 = 20 rad/s.
// The contact point does not slide (w x n = 0), so only the rolling torque acts:
//   edem: mu_r (r - delta/2) m g, cdt: 0 (twist removed), legacy: mu_r R* m g with R* = r,
// so w_z(t) = w0 - M t / I. Checked after 0.05 s within 1% of the expected change (cdt: w_z
// stays w0 to 1e-9).
TEST_P(FloorRollingTest, PureTwistAboutTheNormal) {
  const auto [model, floor] = GetParam();
  const std::unique_ptr<System> owner = FloorSystem(model, floor);
  System& s = *owner;
  const double delta = RestingOverlap(), w0 = 20.0;
  s.AddParticle({0, 0, kRadius - delta}, {}, {0, 0, w0}, kRadius, 0);
  const double t_end = 0.05;
  while (s.time() < t_end) test::StepOk(s);
  const double w = s.particles().w[0].z;
  const double lever = model == RollingModel::kEdem ? kRadius - 0.5 * delta : kRadius;
  const double expected = model == RollingModel::kCdt ? 0.0 : kMuR * lever * Mass() * kG;
  const double change = w0 - w;
  if (model == RollingModel::kCdt) {
    EXPECT_NEAR(w, w0, 1e-9 * w0);
  } else {
    EXPECT_NEAR(change, expected * s.time() / Inertia(), 0.01 * expected * s.time() / Inertia());
  }
  EXPECT_NEAR(Norm(s.particles().v[0]), 0.0, 1e-9);  // no sliding
}

// Rolling without slip: the torque mu_r R m g (R = r, or r - delta/2 for edem: 1e-4 r here)
// decelerates the sphere at a = 5/7 mu_r g (torque balance with I = 2/5 m r^2), under each model.
// Within 2%, fitted by least squares over 0.3 s.
TEST_P(FloorRollingTest, RollingDeceleratesAtFiveSeventhsMuRG) {
  const auto [model, floor] = GetParam();
  const std::unique_ptr<System> owner = FloorSystem(model, floor);
  System& s = *owner;
  const double v0 = 0.05;
  s.AddParticle({0, 0, kRadius - RestingOverlap()}, {v0, 0, 0}, {0, v0 / kRadius, 0}, kRadius, 0);
  test::StepOk(s, 2000);  // let the tangential spring load up
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  const double t_end = s.time() + 0.3;
  while (s.time() < t_end) {
    test::StepOk(s);
    const double t = s.time(), v = s.particles().v[0].x;
    st += t;
    sv += v;
    stt += t * t;
    stv += t * v;
    ++n;
  }
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  const double expected = -5.0 / 7.0 * kMuR * kG;
  EXPECT_NEAR(slope, expected, 0.02 * std::abs(expected));
}

std::string FloorName(const ::testing::TestParamInfo<FloorRollingTest::ParamType>& info) {
  return std::string(Name(std::get<0>(info.param))) +
         (std::get<1>(info.param) == Floor::kPlane ? "_plane" : "_mesh");
}

INSTANTIATE_TEST_SUITE_P(Models, FloorRollingTest,
                         ::testing::Combine(::testing::Values(RollingModel::kEdem,
                                                              RollingModel::kCdt,
                                                              RollingModel::kLegacy),
                                            ::testing::Values(Floor::kPlane, Floor::kMesh)),
                         FloorName);

// The mesh's torque leaves the rolling couples out by default (as EDEM) and counts them with
// SystemConfig::mesh_rolling_torque: a sphere twisting on a mesh floor (no tangential force)
// puts exactly -M_particle on the mesh with the option, nothing about z without it.
TEST(MeshRollingTorqueTest, CountedOnlyWhenAsked) {
  for (const bool counted : {false, true}) {
    const std::unique_ptr<System> owner = FloorSystem(RollingModel::kLegacy, Floor::kMesh, counted);
    System& s = *owner;
    s.AddParticle({0, 0, kRadius - RestingOverlap()}, {}, {0, 0, 20.0}, kRadius, 0);
    test::StepOk(s);
    const double on_particle = s.particles().t[0].z;  // -mu_r r F_n
    ASSERT_LT(on_particle, 0.0);
    EXPECT_NEAR(s.mesh_wrench(0).torque.z, counted ? -on_particle : 0.0,
                1e-12 * std::abs(on_particle))
        << (counted ? "counted" : "left out");
  }
}

// Two spheres, a (id 0) and b (id 1), overlapping by delta along x, no gravity; one step. With
// `mixed`, a third sphere c of the other material touches b from the far side, so the batch
// holds two material pairs (the per-contact kernel) and the pair b-c rolls by another model.
struct Pair {
  std::unique_ptr<System> s;
  double delta, fn;  // overlap [m] and Hertz force at it [N]
};

Pair TouchingPair(RollingModel model, bool mixed, const Vec3& w_a, const Vec3& w_b,
                  const Vec3& v_a = {}, const Vec3& v_b = {}) {
  MaterialTable t;
  t.Add(test::Snow());
  t.Add(test::Steel());
  const RollingModel other = model == RollingModel::kCdt ? RollingModel::kEdem : RollingModel::kCdt;
  t.SetInteraction(0, 0, {0.5, 0.58, kMuR, model, DampingLaw::kExactRestitution});
  t.SetInteraction(0, 1, {0.5, 0.58, kMuR, other, DampingLaw::kExactRestitution});
  t.SetInteraction(1, 1, {0.5, 0.58, kMuR, other, DampingLaw::kExactRestitution});
  Pair p{std::make_unique<System>(std::move(t), Config(0.0)), 2e-6, 0};
  p.s->set_num_threads(1);
  const double half = kRadius - 0.5 * p.delta;
  p.s->AddParticle({-half, 0, 0}, v_a, w_a, kRadius, 0);
  p.s->AddParticle({half, 0, 0}, v_b, w_b, kRadius, 0);
  if (mixed) p.s->AddParticle({3 * kRadius - p.delta, 0, 0}, {}, {}, kRadius, 1);
  const PairConstants pc = MakePairConstants(test::Snow(), test::Snow(), {});
  p.fn = HertzForce(pc.e_star, 0.5 * kRadius, p.delta);
  test::StepOk(*p.s);
  return p;
}

// The rolling part of the torque on particle `id`: its torque less r n x F_t, with F_t the
// tangential part of its force (the contact it has with the other of the pair, n from it to
// the other; the forces were evaluated this step).
Vec3 RollingPart(const System& s, int64_t id) {
  const Particles& p = s.particles();
  size_t i = 0, o = 0;
  for (size_t k = 0; k < p.size(); ++k) {
    if (p.id[k] == id) i = k;
    if (p.id[k] == 1 - id) o = k;
  }
  const Vec3 n = (1.0 / Norm(p.x[o] - p.x[i])) * (p.x[o] - p.x[i]);
  const Vec3 ft = p.f[i] - Dot(p.f[i], n) * n;
  return p.t[i] - p.radius[i] * Cross(n, ft);
}

class PairRollingTest : public ::testing::TestWithParam<std::tuple<RollingModel, bool>> {};

// Twist between two spheres: a spins about the line of centres at 20 rad/s, b is still. The
// contact point does not slide, so the torque on a is the rolling torque alone:
//   edem: -mu_r F_n (r - delta/2) on a, none on b (b does not spin);
//   cdt: none; legacy: -mu_r F_n R* (R* = r/2) on a, +that on b.
// F_n is the Hertz force at the overlap (no normal velocity). Within 1e-3 (the step moves them).
TEST_P(PairRollingTest, TwistAboutTheLineOfCentres) {
  const auto [model, mixed] = GetParam();
  const Pair p = TouchingPair(model, mixed, {20.0, 0, 0}, {});
  const Vec3 on_a = RollingPart(*p.s, 0), on_b = RollingPart(*p.s, 1);
  const double scale = kMuR * p.fn * kRadius;
  double a_x = 0, b_x = 0;
  if (model == RollingModel::kEdem) a_x = -kMuR * p.fn * (kRadius - 0.5 * p.delta);
  if (model == RollingModel::kLegacy) a_x = -kMuR * p.fn * 0.5 * kRadius, b_x = -a_x;
  EXPECT_NEAR(on_a.x, a_x, 1e-3 * scale);
  if (!mixed) {  // with c, b feels the b-c contact too
    EXPECT_NEAR(on_b.x, b_x, 1e-3 * scale);
  }
  EXPECT_NEAR(std::hypot(on_a.y, on_a.z), 0.0, 1e-9 * scale);
}

// Two spheres spinning together as one rigid body (w = 10 rad/s about z through their middle,
// v = w x (x - c)): no relative rotation. cdt and legacy apply no rolling torque (1e-9 of
// mu_r F_n r); edem brakes each sphere by its own spin, -mu_r F_n (r - delta/2) each, so the
// pair as a whole feels -2 mu_r F_n (r - delta/2) = -3.05e-7 N m here. Within 1e-3.
class PairCoRotationTest : public ::testing::TestWithParam<RollingModel> {};

TEST_P(PairCoRotationTest, RigidCoRotation) {
  const RollingModel model = GetParam();
  const double w = 10.0, half = kRadius - 1e-6;
  const Pair p =
      TouchingPair(model, false, {0, 0, w}, {0, 0, w}, {0, -w * half, 0}, {0, w * half, 0});
  const Vec3 on_a = RollingPart(*p.s, 0), on_b = RollingPart(*p.s, 1);
  const double scale = kMuR * p.fn * kRadius;
  const double each = model == RollingModel::kEdem ? -kMuR * p.fn * (kRadius - 0.5 * p.delta) : 0;
  EXPECT_NEAR(on_a.z, each, model == RollingModel::kEdem ? 1e-3 * scale : 1e-9 * scale);
  EXPECT_NEAR(on_b.z, each, model == RollingModel::kEdem ? 1e-3 * scale : 1e-9 * scale);
  if (model == RollingModel::kEdem) {
    std::printf("edem brakes a rigidly co-rotating pair by %.3g N m (mu_r F_n = %.3g N)\n",
                on_a.z + on_b.z, kMuR * p.fn);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, PairCoRotationTest,
                         ::testing::Values(RollingModel::kEdem, RollingModel::kCdt,
                                           RollingModel::kLegacy),
                         [](const auto& info) { return std::string(Name(info.param)); });

std::string PairName(const ::testing::TestParamInfo<PairRollingTest::ParamType>& info) {
  return std::string(Name(std::get<0>(info.param))) +
         (std::get<1>(info.param) ? "_mixed" : "_one_pair");
}

INSTANTIATE_TEST_SUITE_P(Models, PairRollingTest,
                         ::testing::Combine(::testing::Values(RollingModel::kEdem,
                                                              RollingModel::kCdt,
                                                              RollingModel::kLegacy),
                                            ::testing::Bool()),
                         PairName);

}  // namespace
}  // namespace dem

// The force pass (dem/force_pass.cpp) against closed forms: binary collisions (the batched
// particle-particle kernel) and sliding/rolling on a plane (the particle-plane contacts).
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "dem/contact.h"
#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;  // 3.5 mm snow sphere [m]

SystemConfig FreeConfig(double rayleigh_fraction) {
  SystemConfig c;
  c.gravity = Vec3{0, 0, 0};
  c.time_step = rayleigh_fraction * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  c.domain_min = Vec3{-0.02, -0.02, -0.02};
  c.domain_max = Vec3{0.02, 0.02, 0.02};
  c.max_speed = 10.0;
  return c;
}

// Steps until the two sides have separated and moved apart by a further skin; returns false on
// a timeout.
template <typename Separated>
bool RunUntil(System& s, Separated separated, int64_t max_steps) {
  for (int64_t k = 0; k < max_steps; ++k) {
    const StepStatus st = s.Step();
    if (!st.ok()) {
      ADD_FAILURE() << st.message;
      return false;
    }
    if (separated()) return true;
  }
  return false;
}

// Head-on collisions under each damping law, for e in {0.88, 0.5} and impact speeds 0.01, 0.1,
// 1 m/s (with this damping form the restitution is speed independent). v_out / v_in within 1% of
//   exact_restitution: e;
//   standard (beta = -ln e / sqrt(ln^2 e + pi^2)): the restitution that beta gives a Hertz
//     impact, test::HertzImpactRestitution (0.883 for e = 0.88, 0.550 for e = 0.5).
class RestitutionTest : public ::testing::TestWithParam<std::tuple<DampingLaw, double, double>> {};

double ExpectedRestitution(DampingLaw law, double e, double r_star, double m_star,
                           const Material& other) {
  if (law == DampingLaw::kExactRestitution) return e;
  const PairConstants pc = MakePairConstants(test::Snow(), other, {});
  return test::HertzImpactRestitution(StandardBeta(e), pc.e_star, r_star, m_star, 0.1);
}

TEST_P(RestitutionTest, SphereSphereHeadOn) {
  const auto [law, e, speed] = GetParam();
  const Interaction in{e, 0.58, 0.05, RollingModel::kEdem, law};
  System s(test::SnowAndSteel(in, in), FreeConfig(0.1));
  s.set_num_threads(1);
  const double gap = 1e-5;
  s.AddParticle({-kRadius - gap, 0, 0}, {0.5 * speed, 0, 0}, {}, kRadius, 0);
  s.AddParticle({kRadius + gap, 0, 0}, {-0.5 * speed, 0, 0}, {}, kRadius, 0);
  auto rel = [&] {
    const Particles& p = s.particles();
    const size_t a = p.id[0] == 0 ? 0 : 1, b = 1 - a;
    return std::make_pair(p.x[b].x - p.x[a].x, p.v[b].x - p.v[a].x);
  };
  ASSERT_TRUE(RunUntil(
      s,
      [&] {
        const auto [d, vr] = rel();
        return vr > 0 && d > 2 * kRadius + gap;
      },
      2'000'000));
  const double m = s.particles().mass[0];
  const double expected = ExpectedRestitution(law, e, 0.5 * kRadius, 0.5 * m, test::Snow());
  EXPECT_NEAR(rel().second / speed, expected, 0.01 * expected) << "speed " << speed;
}

TEST_P(RestitutionTest, SpherePlaneHeadOn) {
  const auto [law, e, speed] = GetParam();
  SystemConfig c = FreeConfig(0.1);
  c.planes.push_back(test::Floor(0.0, 1));
  const Interaction in{e, 0.58, 0.05, RollingModel::kEdem, law};
  System s(test::SnowAndSteel(in, in), c);
  s.set_num_threads(1);
  s.AddParticle({0, 0, kRadius + 1e-5}, {0, 0, -speed}, {}, kRadius, 0);
  ASSERT_TRUE(RunUntil(
      s,
      [&] {
        const Particles& p = s.particles();
        return p.v[0].z > 0 && p.x[0].z > kRadius + 1e-5;
      },
      2'000'000));
  const double expected =
      ExpectedRestitution(law, e, kRadius, s.particles().mass[0], test::Steel());
  EXPECT_NEAR(s.particles().v[0].z / speed, expected, 0.01 * expected) << "speed " << speed;
}

INSTANTIATE_TEST_SUITE_P(
    Speeds, RestitutionTest,
    ::testing::Combine(::testing::Values(DampingLaw::kExactRestitution, DampingLaw::kStandard),
                       ::testing::Values(0.88, 0.5), ::testing::Values(0.01, 0.1, 1.0)));

// A sphere launched without spin on a plane slides with deceleration mu g while friction spins it
// up; pure rolling starts at t = 2 v0 / (7 mu g) with speed 5/7 v0 (mu_r = 0). Within 1%.
TEST(RollingTest, SlidingToRollingTransition) {
  const double mu = 0.58, g = 1.3, v0 = 0.05;
  SystemConfig c = FreeConfig(0.2);
  c.gravity = Vec3{0, 0, -g};
  c.domain_min = Vec3{-0.01, -0.01, -0.01};
  c.domain_max = Vec3{0.05, 0.01, 0.01};
  c.planes.push_back(test::Floor(0.0, 1));
  System s(test::SnowAndSteel({0.5, mu, 0.0}, {0.5, mu, 0.0}), c);
  s.set_num_threads(1);
  // Start at the static Hertz overlap so the normal force is m g from the first step.
  const double mass = 300.0 * 4.0 / 3.0 * M_PI * std::pow(kRadius, 3);
  const PairConstants pc = MakePairConstants(test::Snow(), test::Steel(), {0.5, mu, 0.0});
  const double delta = std::pow(mass * g / (4.0 / 3.0 * pc.e_star * std::sqrt(kRadius)), 2.0 / 3);
  s.AddParticle({0, 0, kRadius - delta}, {v0, 0, 0}, {}, kRadius, 0);
  const double t_roll = 2 * v0 / (7 * mu * g);
  double t_found = -1, v_found = 0;
  for (int64_t k = 0; k < 100000 && t_found < 0; ++k) {
    test::StepOk(s);
    const Particles& p = s.particles();
    const double slip = p.v[0].x - kRadius * p.w[0].y;  // contact-point speed
    if (slip <= 1e-4 * v0) {
      t_found = s.time();
      v_found = p.v[0].x;
    }
  }
  EXPECT_NEAR(t_found, t_roll, 0.01 * t_roll);
  EXPECT_NEAR(v_found, 5.0 / 7.0 * v0, 0.01 * 5.0 / 7.0 * v0);
}

}  // namespace
}  // namespace dem

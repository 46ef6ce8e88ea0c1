// The step's health checks and diagnoses (dem/diagnostics.cpp): each bad state is reported with
// the offending particle, the time and the knob to turn.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;

SystemConfig TwoSphereConfig() {
  SystemConfig c;
  c.gravity = Vec3{0, 0, 0};
  c.time_step = 0.2 * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  c.domain_min = Vec3{-0.02, -0.02, -0.02};
  c.domain_max = Vec3{0.02, 0.02, 0.02};
  c.max_speed = 10.0;
  c.max_overlap_fraction = 0.05;
  return c;
}

// The reported deepest overlap is delta / (2 min(r_i, r_j)): spheres of r and r/2 placed 3% of
// the small one's diameter into each other, at rest, so the first step's force pass sees them
// where they were put (relative 1e-9, round-off of the positions).
TEST(HealthTest, ReportsDeepestOverlapAsFractionOfTheSmallerDiameter) {
  const Interaction law{0.5, 0.5, 0.0};
  System s(test::SnowAndSteel(law, law), TwoSphereConfig());
  s.set_num_threads(1);
  const double delta = 0.03 * kRadius;  // 3% of the small sphere's diameter (kRadius)
  s.AddParticle({0, 0, 0}, {}, {}, kRadius, 0);
  s.AddParticle({1.5 * kRadius - delta, 0, 0}, {}, {}, 0.5 * kRadius, 0);
  ASSERT_TRUE(s.Step().ok());
  EXPECT_NEAR(s.neighbor_stats().max_overlap, 0.03, 0.03 * 1e-9);
}

// Health checks (STYLE.md habit 8): each bad state is reported with the offending particle's
// persistent id, the time and the scene knob to turn.
TEST(HealthTest, ReportsOverlapSpeedAndNonFiniteState) {
  const Interaction law{0.5, 0.5, 0.0};
  {  // Two spheres placed 20% of a diameter into each other.
    System s(test::SnowAndSteel(law, law), TwoSphereConfig());
    s.set_num_threads(1);
    s.AddParticle({0, 0, 0}, {}, {}, kRadius, 0);
    s.AddParticle({1.6 * kRadius, 0, 0}, {}, {}, kRadius, 0);
    const StepStatus st = s.Step();
    EXPECT_TRUE(st.flags & kExcessiveOverlap);
    EXPECT_EQ(st.particle, 0);
    // It names the partner of the deepest overlap.
    EXPECT_NE(st.message.find("against particle 1 "), std::string::npos) << st.message;
    EXPECT_NE(st.message.find("rayleigh_fraction"), std::string::npos) << st.message;
    EXPECT_NE(st.message.find("t = "), std::string::npos) << st.message;
  }
  {  // A sphere thrown at 50 m/s with a 10 m/s runaway limit.
    System s(test::SnowAndSteel(law, law), TwoSphereConfig());
    s.set_num_threads(1);
    s.AddParticle({0, 0, 0}, {}, {}, kRadius, 0);
    s.AddParticle({0.01, 0, 0}, {50, 0, 0}, {}, kRadius, 0);
    const StepStatus st = s.Step();
    EXPECT_TRUE(st.flags & kRunawaySpeed);
    EXPECT_EQ(st.particle, 1);
    EXPECT_NE(st.message.find("particle 1 moves at 50"), std::string::npos) << st.message;
  }
  {  // A NaN velocity.
    System s(test::SnowAndSteel(law, law), TwoSphereConfig());
    s.set_num_threads(1);
    s.AddParticle({0, 0, 0}, {std::nan(""), 0, 0}, {}, kRadius, 0);
    const StepStatus st = s.Step();
    EXPECT_TRUE(st.flags & kNonFinite);
    EXPECT_EQ(st.particle, 0);
    EXPECT_NE(st.message.find("non-finite"), std::string::npos) << st.message;
  }
}

}  // namespace
}  // namespace dem

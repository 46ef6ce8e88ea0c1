// The System's step as a whole (dem/system.cpp running the phases of dem/internal_phases.h):
// conservation laws of the integrator and force pass, and determinism across thread counts.
#include <gtest/gtest.h>

#include <cmath>

#include "dem/insertion.h"
#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;

// Closed box of six walls, `n` spheres on a jittered lattice with random velocities.
std::unique_ptr<System> Gas(int n, double speed, const Interaction& law, const Vec3& gravity,
                            bool walls, uint64_t seed, int threads) {
  SystemConfig c;
  c.gravity = gravity;
  c.time_step = 0.2 * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  const Vec3 lo{0, 0, 0}, hi{0.1, 0.05, 0.05};
  c.domain_min = lo;
  c.domain_max = hi;
  if (walls) {
    c.planes = {{"z0", lo, {0, 0, 1}, 1},  {"z1", hi, {0, 0, -1}, 1}, {"x0", lo, {1, 0, 0}, 1},
                {"x1", hi, {-1, 0, 0}, 1}, {"y0", lo, {0, 1, 0}, 1},  {"y1", hi, {0, -1, 0}, 1}};
  }
  auto s = std::make_unique<System>(test::SnowAndSteel(law, law), c);
  s->set_num_threads(threads);
  Rng rng(seed);
  for (const SphereSeed& p : InsertSpheres(lo, hi, n, kRadius, kRadius, 0.2, rng)) {
    const Vec3 v{rng.Uniform(-speed, speed), rng.Uniform(-speed, speed),
                 rng.Uniform(-speed, speed)};
    s->AddParticle(p.x, v, {}, p.radius, 0);
  }
  EXPECT_EQ(static_cast<int>(s->particles().size()), n);
  return s;
}

// e = 1, no friction: no force dissipates, so KE + gravity PE + Hertz elastic energy is constant
// up to the integrator's error. 2000 spheres, 10,000 steps at 0.2 t_R: within 0.5%.
TEST(ConservationTest, ElasticFrictionlessBoxKeepsEnergy) {
  auto s = Gas(2000, 0.3, {1.0, 0.0, 0.0}, {0, 0, -1.3}, true, 11, 2);
  auto total = [&] { return s->KineticEnergy() + s->PotentialEnergy() + s->ElasticEnergy(); };
  test::StepOk(*s);
  const double e0 = total();
  int64_t collisions_seen = 0;
  for (int k = 0; k < 100; ++k) {
    test::StepOk(*s, 100);
    collisions_seen += s->neighbor_stats().contacts;
    EXPECT_NEAR(total(), e0, 0.005 * e0) << "step " << s->step_count();
  }
  EXPECT_GT(collisions_seen, 100) << "the test must exercise contacts";
}

// No gravity, no walls: contact forces are applied as exact +/- pairs, so total momentum stays
// constant to round-off (1e-12 of the sum of |m v|), with friction, damping and rolling friction.
TEST(ConservationTest, MomentumConservedWithoutExternalForces) {
  auto s = Gas(2000, 0.3, {0.5, 0.58, 0.05}, {0, 0, 0}, false, 12, 2);
  double scale = 0;
  for (size_t i = 0; i < s->particles().size(); ++i)
    scale += s->particles().mass[i] * Norm(s->particles().v[i]);
  const Vec3 p0 = s->Momentum();
  int64_t contacts = 0;
  for (int k = 0; k < 20; ++k) {
    test::StepOk(*s, 100);
    contacts += s->neighbor_stats().contacts;
    const Vec3 p = s->Momentum();
    EXPECT_NEAR(p.x, p0.x, 1e-12 * scale);
    EXPECT_NEAR(p.y, p0.y, 1e-12 * scale);
    EXPECT_NEAR(p.z, p0.z, 1e-12 * scale);
  }
  EXPECT_GT(contacts, 100);
}

// Determinism: the same system stepped with 1, 2 (twice) and 3 threads gives the same state hash
// bit for bit (fixed pair order, no floating-point atomics; the force pass's slabs go to threads
// by weight and are taken over by whichever thread is free, which must change no sum).
TEST(DeterminismTest, StateHashIndependentOfThreadCount) {
  uint64_t hashes[4];
  const int threads[4] = {1, 2, 2, 3};
  for (int r = 0; r < 4; ++r) {
    auto s = Gas(2000, 0.3, {0.88, 0.58, 0.05}, {0, 0, -1.3}, true, 13, threads[r]);
    test::StepOk(*s, 1500);
    hashes[r] = s->StateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
  EXPECT_EQ(hashes[1], hashes[2]);
  EXPECT_EQ(hashes[2], hashes[3]);
}

// SaveState / RestoreState: a System restored into a fresh one of the same model (here with
// sleeping on, friction and walls, on another thread count) steps on bit for bit: the same state
// hash and contact history 800 steps later, and the same bytes saved again.
TEST(StateTest, RestoredSystemStepsOnBitForBit) {
  SleepConfig sleep;
  sleep.enabled = true;
  sleep.speed = 0.05;  // some sleep and wake within the run
  sleep.check_every = 20;
  auto a = Gas(2000, 0.3, {0.5, 0.5, 0.05}, {0, 0, -9.81}, true, 21, 2);
  a->set_sleep(sleep);
  test::StepOk(*a, 700);
  auto b = Gas(0, 0.3, {0.5, 0.5, 0.05}, {0, 0, -9.81}, true, 21, 1);
  b->set_sleep(sleep);
  b->RestoreState(a->SaveState());
  EXPECT_EQ(b->StateHash(), a->StateHash());
  test::StepOk(*a, 800);
  test::StepOk(*b, 800);
  EXPECT_EQ(b->StateHash(), a->StateHash());
  EXPECT_LT(a->awake_count(), 2000);
  const std::vector<ContactRecord> ca = a->Contacts(), cb = b->Contacts();
  ASSERT_EQ(cb.size(), ca.size());
  for (size_t k = 0; k < ca.size(); ++k) {
    EXPECT_EQ(cb[k].a, ca[k].a);
    EXPECT_EQ(cb[k].b, ca[k].b);
    EXPECT_EQ(cb[k].shear.x, ca[k].shear.x);
  }
  EXPECT_TRUE(b->SaveState() == a->SaveState());
  // Bytes of another layout are refused.
  std::vector<char> bad = a->SaveState();
  bad.resize(bad.size() / 2);
  auto c = Gas(0, 0.3, {0.5, 0.5, 0.05}, {0, 0, -9.81}, true, 21, 1);
  EXPECT_THROW(c->RestoreState(bad), std::runtime_error);
}

}  // namespace
}  // namespace dem

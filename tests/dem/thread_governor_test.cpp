// The thread governor (dem/thread_governor.h) on made-up step times: it keeps the faster count,
// comes back when the load goes, probes less while nothing changes; and a System whose count
// changes at nearly every step still gives the 1-thread state hash bit for bit.
#include "dem/thread_governor.h"

#include <gtest/gtest.h>

#include <functional>

#include "dem/insertion.h"
#include "tests/dem/test_util.h"

namespace dem {
namespace {

// Steps the governor for `wall` seconds of made-up time, a step at n threads costing cost(n) [s];
// every 50th step rebuilds and costs 20 plain steps.
void Drive(ThreadGovernor& g, double wall, const std::function<double(int)>& cost) {
  for (double t = 0; t < wall;) {
    const bool rebuilt = g.steps() % 50 == 49;
    const double s = cost(g.threads()) * (rebuilt ? 20.0 : 1.0);
    g.Record(s, rebuilt);
    t += s;
  }
}

// Another process holds a core: two threads wait at every barrier, a step costs 3 ms against
// 1 ms on one thread. The first probe (after 0.05 s) moves to one thread for good.
TEST(ThreadGovernorTest, ABusyCoreMovesToOneThread) {
  ThreadGovernor g(2);
  Drive(g, 120.0, [](int n) { return n == 2 ? 3e-3 : 1e-3; });
  EXPECT_EQ(g.current(), 1);
  EXPECT_EQ(g.switches(), 1);
  EXPECT_GT(g.steps_fewer(), 0.98 * g.steps());
}

// Spinning threads on a loaded host: two threads 20x slower. Back on one thread, each probe of
// two gives up once its window has taken 1.5x the one-thread window (20 ms): over 60 s, under
// 1% of the time goes to probing.
TEST(ThreadGovernorTest, AProbeOfAFarSlowerCountEndsEarly) {
  ThreadGovernor g(2);
  double at_two = 0;
  for (double t = 0; t < 60.0;) {
    const double s = g.threads() == 2 ? 20e-3 : 1e-3;
    if (g.threads() == 2) at_two += s;
    g.Record(s, false);
    t += s;
  }
  EXPECT_EQ(g.current(), 1);
  EXPECT_LT(at_two, 0.01 * 60.0);
  EXPECT_GE(g.probes(), 5);
}

// A quiet machine: two threads twice as fast; the count stays, and the probes thin out (the
// interval doubles from 2 s to 60 s): 7 probes in 120 s.
TEST(ThreadGovernorTest, AQuietMachineKeepsTheConfiguredCount) {
  ThreadGovernor g(2);
  Drive(g, 120.0, [](int n) { return n == 2 ? 0.5e-3 : 1e-3; });
  EXPECT_EQ(g.current(), 2);
  EXPECT_EQ(g.switches(), 0);
  EXPECT_LE(g.probes(), 8);
  EXPECT_LT(g.steps_fewer(), 0.01 * g.steps());
}

// The load goes after 30 s: back to two threads within the next probe (at most 2 s + 4 s + ...
// of doubling, here under 40 s).
TEST(ThreadGovernorTest, ComesBackWhenTheLoadGoes) {
  ThreadGovernor g(2);
  Drive(g, 30.0, [](int n) { return n == 2 ? 3e-3 : 1e-3; });
  ASSERT_EQ(g.current(), 1);
  Drive(g, 40.0, [](int n) { return n == 2 ? 0.5e-3 : 1e-3; });
  EXPECT_EQ(g.current(), 2);
}

// Four threads configured, two cores held (each thread beyond two costs more): down one thread
// a probe, to the count that is fastest (here two), and no further. (A hill climb: a count no
// faster than its neighbour stops it.)
TEST(ThreadGovernorTest, StepsDownToTheFastestCount) {
  ThreadGovernor g(4);
  const auto cost = [](int n) { return n > 2 ? 1e-3 * n : 1e-3 / n; };
  Drive(g, 60.0, cost);
  EXPECT_EQ(g.current(), 2);
}

TEST(ThreadGovernorTest, OneThreadNeverProbes) {
  ThreadGovernor g(1);
  Drive(g, 10.0, [](int) { return 1e-3; });
  EXPECT_EQ(g.threads(), 1);
  EXPECT_EQ(g.probes(), 0);
}

// A System whose governor probes all the time and always takes the other count (so the count
// changes every few steps, in the middle of neighbour and near
// list lifetimes) gives the state hash of one thread.
TEST(ThreadGovernorTest, CountChangingEveryFewStepsKeepsTheHash) {
  uint64_t hash[2];
  int64_t switches = 0;
  for (const bool adaptive : {false, true}) {
    SystemConfig c;
    c.gravity = {0, 0, -1.3};
    c.time_step = 0.2 * RayleighTimeStep(1.75e-3, test::Snow());
    c.skin = 0.875e-3;
    const Vec3 lo{0, 0, 0}, hi{0.1, 0.05, 0.05};
    c.domain_min = lo;
    c.domain_max = hi;
    c.planes = {{"z0", lo, {0, 0, 1}, 1},
                {"x0", lo, {1, 0, 0}, 1},
                {"x1", hi, {-1, 0, 0}, 1},
                {"y0", lo, {0, 1, 0}, 1},
                {"y1", hi, {0, -1, 0}, 1}};
    const Interaction law{0.88, 0.58, 0.05};
    System s(test::SnowAndSteel(law, law), c);
    s.set_num_threads(adaptive ? 2 : 1);
    if (adaptive) {
      GovernorConfig gc;
      gc.window = 0;
      gc.first_interval = gc.interval = gc.max_interval = 0;
      gc.switch_below = 1e9;  // always
      gc.give_up_above = 1e9;
      s.set_adaptive_threads(true, gc);
    }
    Rng rng(13);
    for (const SphereSeed& p : InsertSpheres(lo, hi, 2000, 1.75e-3, 1.75e-3, 0.2, rng))
      s.AddParticle(p.x, {rng.Uniform(-0.3, 0.3), rng.Uniform(-0.3, 0.3), 0}, {}, p.radius, 0);
    test::StepOk(s, 1500);
    hash[adaptive] = s.StateHash();
    if (adaptive) switches = s.governor()->switches();
  }
  EXPECT_GT(switches, 100);
  EXPECT_EQ(hash[1], hash[0]);
}

}  // namespace
}  // namespace dem

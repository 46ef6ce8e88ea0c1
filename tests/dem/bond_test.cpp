// The parallel bond (dem/bond.h): a bonded pair against its closed forms in tension, shear,
// bending and twist, and at break; a bonded chain as a cantilever against its discrete closed form
// and Euler-Bernoulli; the critical step on a bonded lattice; determinism, save and restore, and
// the bond calls' checks.
#include "dem/bond.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "dem/system.h"
#include "test_util.h"

namespace dem {
namespace {

constexpr double kR = 0.005;  // sphere radius [m]

// One material: snow (paper Table 6); contacts between spheres act as ever.
MaterialTable SnowOnly() {
  MaterialTable t;
  t.Add(test::Snow());
  t.SetInteraction(0, 0, {0.5, 0.5, 0.0});
  return t;
}

// Bond parameters: E_b 1e8 Pa (k_n = E_b / 2r = 1e10 Pa/m), k_n / k_s = 2 (so that swapping the
// two stiffnesses shows), strengths 1e5 Pa, friction angle 30 degrees.
BondParams Params() {
  BondParams b;
  b.radius_multiplier = 1.0;
  b.modulus = 1e8;
  b.stiffness_ratio = 2.0;
  b.tensile_strength = 1e5;
  b.cohesion = 1e5;
  b.friction_angle = M_PI / 6;
  return b;
}

std::unique_ptr<System> MakeSystem(double dt, const Vec3& gravity = {0, 0, 0}, int threads = 1) {
  SystemConfig c;
  c.gravity = gravity;
  c.time_step = dt;
  c.skin = 0.2 * kR;
  c.domain_min = {-0.5, -0.5, -0.5};
  c.domain_max = {0.5, 0.5, 0.5};
  auto s = std::make_unique<System>(SnowOnly(), c);
  s->set_num_threads(threads);
  return s;
}

size_t IndexOf(const System& s, int64_t id) {
  const Particles& p = s.particles();
  return static_cast<size_t>(std::find(p.id.begin(), p.id.end(), id) - p.id.begin());
}

// Makes sphere `id` kinematic: infinite mass and inertia (the kicks leave v and w as set), moving
// at v and spinning at w.
void Drive(System& s, int64_t id, const Vec3& v, const Vec3& w) {
  Particles& p = s.mutable_particles();
  const size_t i = IndexOf(s, id);
  p.inv_mass[i] = 0;
  p.inv_inertia[i] = 0;
  p.v[i] = v;
  p.w[i] = w;
  s.Touch();  // the particles are no longer alike (Workspace::alike)
}

// Two spheres on the x axis, centres `distance` apart, bonded; both driven (a at rest).
struct Pair {
  std::unique_ptr<System> s;
  int64_t a, b;
};
Pair BondedPair(double distance, const BondParams& params, double dt) {
  Pair q;
  q.s = MakeSystem(dt);
  q.a = q.s->AddParticle({0, 0, 0}, {}, {}, kR, 0);
  q.b = q.s->AddParticle({distance, 0, 0}, {}, {}, kR, 0);
  q.s->AddBonds({MakeBond(q.a, kR, q.b, kR, distance, params)});
  Drive(*q.s, q.a, {}, {});
  return q;
}

// Uniform numbers in [-1, 1) from SplitMix64 (a generator whose bits we own).
class Uniform {
 public:
  explicit Uniform(uint64_t seed) : state_(seed) {}
  double operator()() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return 2.0 * static_cast<double>(z >> 11) / 9007199254740992.0 - 1.0;
  }

 private:
  uint64_t state_;
};

// Disk of the bond between two spheres of kR with multiplier 1.
const double kArea = M_PI * kR * kR, kInertia = M_PI * std::pow(kR, 4) / 4,
             kPolar = M_PI * std::pow(kR, 4) / 2;
const double kKn = 1e8 / (2 * kR), kKs = kKn / 2;

// Axial tension at a steady 0.01 m/s (1e-8 m a step): F_n = k_n A u exactly for the incremental
// law with the normal fixed (u = the step count x 1e-8 m), to 1e-9 relative (rounding of the
// sums), and the force on b is -F_n n. It breaks, in tension, at the first step k with
// k_n k du >= sigma_c (k* = 1000 here), within one step: the load increment a step is
// k_n du = 100 Pa of the 1e5 Pa.
TEST(BondTest, AxialTensionStiffnessAndBreak) {
  const double dt = 1e-6, u = 0.01;
  Pair q = BondedPair(2 * kR, Params(), dt);
  Drive(*q.s, q.b, {u, 0, 0}, {});
  const int k_star = static_cast<int>(std::ceil(1e5 / (kKn * u * dt)));
  int broke_at = -1;
  for (int k = 1; k <= 2 * k_star && broke_at < 0; ++k) {
    test::StepOk(*q.s);
    const Bond& b = q.s->bonds()[0];
    if (!b.intact) {
      broke_at = k;
      break;
    }
    const double disp = q.s->particles().x[IndexOf(*q.s, q.b)].x - 2 * kR;
    ASSERT_NEAR(b.fn, kKn * kArea * disp, 1e-9 * kKn * kArea * disp) << "step " << k;
    ASSERT_NEAR(q.s->particles().f[IndexOf(*q.s, q.b)].x, -b.fn, 1e-12 * b.fn);
  }
  EXPECT_NEAR(broke_at, k_star, 1);
  const std::vector<BondBreak> breaks = q.s->TakeBondBreaks();
  ASSERT_EQ(breaks.size(), 1u);
  EXPECT_EQ(breaks[0].mode, BondBreakMode::kTension);
  EXPECT_GE(breaks[0].stress, 1e5);
  EXPECT_LT(breaks[0].stress, 1e5 + kKn * u * dt * 1.001);
  EXPECT_NEAR(breaks[0].position.x, 0.5 * (2 * kR + u * dt * broke_at), 1e-12);
  EXPECT_EQ(q.s->intact_bond_count(), 0);
  // Gone for good: pushed back together, it carries nothing.
  Drive(*q.s, q.b, {-u, 0, 0}, {});
  test::StepOk(*q.s, 10);
  EXPECT_EQ(q.s->particles().f[IndexOf(*q.s, q.b)].x, 0.0);
  EXPECT_TRUE(q.s->TakeBondBreaks().empty());
}

// Shear with the rotations held (both spheres driven, no spin): b moves sideways at 0.01 m/s.
// While the displacement s is small, the shear force on b is -k_s A s along y to 1e-6 relative
// (the normal turns by s / d: the error is O((s/d)^2) ~ 1e-6), the torque on b is the lever's,
// -lever n x F_s, and M_b = 0 (no relative rotation). The shear strength is
// c - (F_n / A) tan(phi): with the bond first compressed to sigma = 5e4 Pa (a 0.2 r gap keeps the
// spheres from touching), it breaks in shear at tau within one step's increment (k_s du = 50 Pa)
// of c - (F_n / A) tan(phi) with the bond's F_n then; the compressed bond's shear strength is
// higher than the unloaded one's by tan(phi) times the difference of their compressive stresses
// (28868 Pa for 5e4 Pa), to 2 increments. The normal force drifts into tension by k_n s^2 / 2d
// (some 200-300 Pa) as b moves aside, which the strength follows.
TEST(BondTest, ShearStiffnessAndMohrCoulombBreak) {
  const double dt = 1e-6, u = 0.01, d0 = 2.2 * kR;
  double tau_break[2] = {0, 0}, sigma_at[2] = {0, 0};
  for (int loaded = 0; loaded < 2; ++loaded) {
    Pair q = BondedPair(d0, Params(), dt);
    // Compression to 5e4 Pa: 5e4 / k_n = 5e-6 m, 500 steps of 1e-8 m.
    if (loaded) {
      Drive(*q.s, q.b, {-u, 0, 0}, {});
      test::StepOk(*q.s, 500);
      EXPECT_NEAR(q.s->bonds()[0].fn / kArea, -5e4, 1e-6 * 5e4);
    }
    Drive(*q.s, q.b, {0, u, 0}, {});
    const double y0 = q.s->particles().x[IndexOf(*q.s, q.b)].y;
    for (int k = 1; k <= 4000; ++k) {
      test::StepOk(*q.s);
      const Bond& b = q.s->bonds()[0];
      if (!b.intact) break;
      if (k == 10) {  // s = 1e-7 m, s / d = 9e-6
        const size_t ib = IndexOf(*q.s, q.b);
        const double s = q.s->particles().x[ib].y - y0;
        EXPECT_NEAR(b.fs.y, -kKs * kArea * s, 1e-6 * kKs * kArea * s);
        EXPECT_NEAR(Norm(b.mb), 0.0, 1e-20);
        const Vec3 xb = q.s->particles().x[ib], xa{0, 0, 0};
        const double dist = Norm(xb - xa);
        const Vec3 n = (1 / dist) * (xb - xa);
        const Vec3 t_expected = -(0.5 * dist) * Cross(n, b.fs - b.fn * n);
        EXPECT_NEAR(q.s->particles().t[ib].z, t_expected.z, 1e-9 * std::abs(t_expected.z));
      }
    }
    ASSERT_FALSE(q.s->bonds()[0].intact);
    const std::vector<BondBreak> breaks = q.s->TakeBondBreaks();
    ASSERT_EQ(breaks.size(), 1u);
    EXPECT_EQ(breaks[0].mode, BondBreakMode::kShear);
    const Bond& b = q.s->bonds()[0];
    const double strength = 1e5 - b.fn / kArea * std::tan(M_PI / 6);
    EXPECT_GE(breaks[0].stress, strength);
    EXPECT_LT(breaks[0].stress, strength + kKs * u * dt * 1.01);
    tau_break[loaded] = breaks[0].stress;
    sigma_at[loaded] = -b.fn / kArea;
  }
  // Unloaded, the strength is c less what the normal force's drift into tension took
  // (k_n s^2 / 2d = 180 Pa at s = 2e-5 m, times tan(phi)).
  EXPECT_NEAR(tau_break[0], 1e5, kKs * u * dt + 0.15e3);
  EXPECT_NEAR(sigma_at[1], 5e4, 0.01 * 5e4);
  EXPECT_NEAR(tau_break[1] - tau_break[0], std::tan(M_PI / 6) * (sigma_at[1] - sigma_at[0]),
              2 * kKs * u * dt);
  EXPECT_GT(tau_break[1] - tau_break[0], 0.98 * std::tan(M_PI / 6) * 5e4);
}

// Bending: b spins about y (perpendicular to n) at 1 rad/s, both centres held: M_b = -k_n I theta
// along y (theta = the step count x dt), exact but for rounding (1e-9). The contact point on b
// moves too, so the shear spring adds its lever: the torque on b is
// -(k_n I + k_s A lever^2) theta along y (lever = r). It breaks in tension when
// sigma = |M_b| R / I = k_n theta R reaches sigma_c.
TEST(BondTest, BendingMoment) {
  const double dt = 1e-6, omega = 1.0;
  Pair q = BondedPair(2 * kR, Params(), dt);
  Drive(*q.s, q.b, {}, {0, omega, 0});
  for (int k = 1; k <= 200; ++k) {
    test::StepOk(*q.s);
    const double theta = omega * dt * k;
    const Bond& b = q.s->bonds()[0];
    ASSERT_NEAR(b.mb.y, -kKn * kInertia * theta, 1e-9 * kKn * kInertia * theta);
    const double t_expected = -(kKn * kInertia + kKs * kArea * kR * kR) * theta;
    ASSERT_NEAR(q.s->particles().t[IndexOf(*q.s, q.b)].y, t_expected, 1e-9 * std::abs(t_expected));
  }
  const int k_break = static_cast<int>(std::ceil(1e5 / (kKn * kR * omega * dt)));  // 2000
  for (int k = 201; k <= 3000 && q.s->bonds()[0].intact; ++k) test::StepOk(*q.s);
  const std::vector<BondBreak> breaks = q.s->TakeBondBreaks();
  ASSERT_EQ(breaks.size(), 1u);
  EXPECT_EQ(breaks[0].mode, BondBreakMode::kTension);
  EXPECT_NEAR(breaks[0].time / dt, k_break, 1.01);
}

// Twist: b spins about n (x) at 1 rad/s: M_t = -k_s J theta, and no shear (the contact point
// lies on the axis): the torque on b is exactly M_t n (1e-9, rounding).
TEST(BondTest, TwistMoment) {
  const double dt = 1e-6, omega = 1.0;
  Pair q = BondedPair(2 * kR, Params(), dt);
  Drive(*q.s, q.b, {}, {omega, 0, 0});
  for (int k = 1; k <= 200; ++k) {
    test::StepOk(*q.s);
    const double theta = omega * dt * k;
    const Bond& b = q.s->bonds()[0];
    ASSERT_NEAR(b.mt, -kKs * kPolar * theta, 1e-9 * kKs * kPolar * theta);
    const Vec3 t = q.s->particles().t[IndexOf(*q.s, q.b)];
    ASSERT_NEAR(t.x, -kKs * kPolar * theta, 1e-9 * kKs * kPolar * theta);
    ASSERT_EQ(Norm2(b.fs), 0.0);
  }
}

// A straight chain of N = 11 spheres along x (spacing s = 2r + 1e-7 m, so that no two touch),
// sphere 0 held (position and rotation), a transverse load P = 1e-5 N on the tip (an impulse
// P dt a step, with every velocity scaled by 1 - 2e-3 a step, mass-proportional damping of
// every mode alike, to bring it to rest: e^-40 after the 40,000 steps). At rest, bond k
// (k = 1..n, n = N - 1) carries the shear P and, about its contact point, the moment
// M_k = P s (n + 1/2 - k); so with theta_k = sum_{j<=k} M_j / (k_n I) and the slip P / (k_s A),
//   w_k = w_{k-1} + (s/2) (theta_{k-1} + theta_k) + P / (k_s A)      (exact discrete chain)
// which the tip meets to 1e-6 (rest and linearity). Against Euler-Bernoulli P L^3 / (3 E I)
// (L = n s, E I = E_b pi R^4 / 4): theta_k is exact at the nodes, the trapezoid sum of it is
// short by 1/(4 n^2), and the shear slip adds 3 kappa / (16 n^2) (kappa = k_n / k_s = 2), so
// w_tip / w_EB = 1 + (3 kappa / 16 - 1/4) / n^2 = 1.00125, met to 1e-4 (the gap's 1e-5 and the
// rest's 1e-6); and within 0.7% (the two terms' sum) of 1 itself.
TEST(BondTest, ChainCantileverMatchesBeamTheory) {
  const int n_spheres = 11, n = n_spheres - 1;
  const double s = 2 * kR + 1e-7, P = 1e-5;
  BondParams params = Params();
  params.tensile_strength = params.cohesion = 1e12;  // never breaks
  const double dt = 0.5 * BondCriticalStep(kR, test::Snow().density, params);
  auto sys = MakeSystem(dt);
  std::vector<int64_t> ids;
  for (int k = 0; k < n_spheres; ++k) ids.push_back(sys->AddParticle({k * s, 0, 0}, {}, {}, kR, 0));
  std::vector<Bond> bonds;
  for (int k = 1; k < n_spheres; ++k)
    bonds.push_back(MakeBond(ids[k - 1], kR, ids[k], kR, s, params));
  sys->AddBonds(bonds);
  Drive(*sys, ids[0], {}, {});
  const double m_tip = sys->particles().mass[IndexOf(*sys, ids.back())];
  for (int step = 0; step < 40000; ++step) {
    test::StepOk(*sys);
    // Half the load's impulse, the damping, the other half: at rest (the mid-step velocity
    // zero) the bonds then carry exactly P (all of it before the scaling would leave
    // P (1 - a) / (1 - a/2)).
    Particles& p = sys->mutable_particles();
    const size_t tip = IndexOf(*sys, ids.back());
    p.v[tip].z -= 0.5 * dt * P / m_tip;
    for (size_t i = 0; i < p.size(); ++i) {
      p.v[i] *= 1 - 2e-3;
      p.w[i] *= 1 - 2e-3;
    }
    p.v[tip].z -= 0.5 * dt * P / m_tip;
  }
  const double w_tip = -sys->particles().x[IndexOf(*sys, ids.back())].z;
  // The discrete chain.
  double theta = 0, w = 0;
  for (int k = 1; k <= n; ++k) {
    const double theta_next = theta + P * s * (n + 0.5 - k) / (kKn * kInertia);
    w += 0.5 * s * (theta + theta_next) + P / (kKs * kArea);
    theta = theta_next;
  }
  EXPECT_NEAR(w_tip, w, 1e-6 * w);
  const double length = n * s, ei = 1e8 * kInertia;
  const double w_eb = P * length * length * length / (3 * ei);
  EXPECT_NEAR(w_tip / w_eb, 1 + (3 * 2.0 / 16 - 0.25) / (n * n), 1e-4);
  EXPECT_NEAR(w_tip / w_eb, 1.0, 0.007);
}

// A 5 x 5 x 5 cubic lattice (spacing 2.04 r: no contacts), bonded to its 6 axis neighbours
// (PairsWithinGap: 300 bonds), every sphere kicked at random (|v| ~ 1e-3 m/s, |w| ~ |v| / r),
// no damping, no gravity. At BondCriticalStep the energy (kinetic + the bonds' elastic) stays
// within 15% of its start over 3000 steps (measured 10%: velocity Verlet's fluctuation of the
// energy taken at full steps, of order (omega dt)^2 / 4 for the fastest modes; at half the step
// it is a quarter of that, between 0.15 and 0.35 of it allowed) and does not drift (the mean over
// the last 500 steps within 3% of that over the first 500); at 3x the step it grows more than
// 100-fold (the lattice goes unstable from about 2x; an fcc lattice, 12 bonds a sphere, from
// 1.5x): the step's factor is neither too tight nor a lie.
double LatticeEnergyGrowth(double step_factor, double* worst) {
  const BondParams params = Params();
  const double dt = step_factor * BondCriticalStep(kR, test::Snow().density, params);
  auto sys = MakeSystem(dt);
  Uniform uniform(12345);
  const double spacing = 2.04 * kR, v0 = 1e-3;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k)
        sys->AddParticle({i * spacing, j * spacing, k * spacing},
                         {v0 * uniform(), v0 * uniform(), v0 * uniform()},
                         {v0 / kR * uniform(), v0 / kR * uniform(), v0 / kR * uniform()}, kR, 0);
  const auto pairs = sys->PairsWithinGap(0.1 * kR);
  EXPECT_EQ(pairs.size(), 300u);
  std::vector<Bond> bonds;
  for (const auto& [a, b] : pairs) bonds.push_back(MakeBond(a, kR, b, kR, spacing, params));
  sys->AddBonds(bonds);
  const double e0 = sys->KineticEnergy();
  double first = 0, last = 0, max_dev = 0;
  const int steps = 3000;
  for (int k = 0; k < steps; ++k) {
    sys->Step();
    const double e = sys->KineticEnergy() + sys->BondEnergy();
    if (!std::isfinite(e)) return 1e300;
    max_dev = std::max(max_dev, std::abs(e - e0) / e0);
    if (k < 500) first += e / 500;
    if (k >= steps - 500) last += e / 500;
  }
  *worst = max_dev;
  return max_dev > 10 ? last / e0 : last / first;  // unstable: the growth; else the drift
}

TEST(BondTest, CriticalStepKeepsEnergyAndThreeTimesItDoesNot) {
  double worst = 0, worst_half = 0;
  const double drift = LatticeEnergyGrowth(1.0, &worst);
  EXPECT_LT(worst, 0.15);
  EXPECT_NEAR(drift, 1.0, 0.03);
  EXPECT_NEAR(LatticeEnergyGrowth(0.5, &worst_half), 1.0, 0.03);
  EXPECT_GT(worst_half / worst, 0.15);
  EXPECT_LT(worst_half / worst, 0.35);
  double worst3 = 0;
  const double growth = LatticeEnergyGrowth(3.0, &worst3);
  EXPECT_GT(growth, 100.0);
}

// A bonded sample that breaks: a 6 x 6 x 6 lattice of touching spheres (contacts and bonds
// together), weak bonds, every sphere kicked at random at up to 0.3 m/s (under gravity, falling
// freely; some 300 of the 540 bonds break within 1500 steps). With sleeping (no gravity, a third
// of the sample kicked), about 100 break and the rest comes to rest: some 190 of the 216 spheres
// asleep at the end, their bonds frozen. On 1 and 2 threads, the same state hash and the same
// breaks, bit for bit, either way.
std::unique_ptr<System> BreakingSample(int threads, bool sleeping) {
  BondParams params = Params();
  params.tensile_strength = params.cohesion = 2e4;
  params.damping_ratio = 0.1;
  const double dt = 0.5 * BondCriticalStep(kR, test::Snow().density, params);
  auto sys = MakeSystem(dt, sleeping ? Vec3{} : Vec3{0, 0, -9.81}, threads);
  if (sleeping) {
    SleepConfig sc;
    sc.enabled = true;
    sc.speed = 0.02;
    sc.check_every = 10;
    sys->set_sleep(sc);
  }
  Uniform uniform(777);
  const double spacing = 2 * kR, v0 = 0.3;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) {
        const Vec3 v{v0 * uniform(), v0 * uniform(), v0 * uniform()};
        sys->AddParticle({i * spacing, j * spacing, k * spacing}, sleeping && i > 1 ? Vec3{} : v,
                         {}, kR, 0);
      }
  std::vector<Bond> bonds;
  for (const auto& [a, b] : sys->PairsWithinGap(0.01 * kR))
    bonds.push_back(MakeBond(a, kR, b, kR, spacing, params));
  sys->AddBonds(bonds);
  return sys;
}

// The samples' state hashes at step 1500 (free fall, sleeping), pinned as the scalar bond pass
// made them (one bond at a time, before the batched pass of dem/bond.cpp): the batched pass does
// the same operations in the same order, lane by lane, so it must give the same bits.
constexpr uint64_t kBreakingSampleHash[2] = {0x657a69452fd138b7, 0xfca9ccb247a30266};

TEST(BondTest, BreaksAreTheSameOnOneAndTwoThreads) {
  for (int sleeping = 0; sleeping < 2; ++sleeping) {
    auto one = BreakingSample(1, sleeping), two = BreakingSample(2, sleeping);
    const int64_t total = one->intact_bond_count();
    EXPECT_EQ(total, 540);
    // intact_bond_count() (the live list's size while the bond index is current, else a count
    // of the record) against a count of bonds() after every step of `two`; reading bonds() every
    // step must not change its bits either (the hashes below).
    int64_t miscounts = 0;
    for (int k = 0; k < 1500; ++k) {
      one->Step();
      two->Step();
      const int64_t counted = two->intact_bond_count();
      int64_t intact = 0;
      for (const Bond& b : two->bonds()) intact += b.intact;
      miscounts += counted != intact;
    }
    EXPECT_EQ(miscounts, 0);
    EXPECT_EQ(one->StateHash(), two->StateHash());
    EXPECT_EQ(one->StateHash(), kBreakingSampleHash[sleeping]) << "sleeping " << sleeping;
    const auto b1 = one->TakeBondBreaks(), b2 = two->TakeBondBreaks();
    EXPECT_GT(b1.size(), 20u);
    EXPECT_LT(b1.size(), static_cast<size_t>(total));
    ASSERT_EQ(b1.size(), b2.size());
    for (size_t k = 0; k < b1.size(); ++k) {
      EXPECT_EQ(b1[k].a, b2[k].a);
      EXPECT_EQ(b1[k].b, b2[k].b);
      EXPECT_EQ(b1[k].time, b2[k].time);
      EXPECT_EQ(b1[k].mode, b2[k].mode);
      EXPECT_EQ(b1[k].stress, b2[k].stress);
    }
    bool tension = false, shear = false;
    for (const BondBreak& b : b1) {
      tension = tension || b.mode == BondBreakMode::kTension;
      shear = shear || b.mode == BondBreakMode::kShear;
    }
    EXPECT_TRUE(tension);
    EXPECT_TRUE(shear);
  }
}

// SaveState / RestoreState with about half the bonds broken (and breaks not yet taken): the
// restored System (on another thread count) steps on bit for bit: the same hash, bonds and breaks.
TEST(BondTest, RestoredStateWithHalfTheBondsBrokenReplays) {
  auto a = BreakingSample(2, false);
  const int64_t total = a->intact_bond_count();
  for (int k = 0; k < 6000 && a->intact_bond_count() > total / 2; ++k) a->Step();
  EXPECT_LE(a->intact_bond_count(), total / 2 + 20);
  EXPECT_GT(a->intact_bond_count(), total / 4);
  a->Canonicalize();
  auto b = MakeSystem(a->config().time_step, a->config().gravity, 1);
  b->RestoreState(a->SaveState());
  EXPECT_EQ(b->StateHash(), a->StateHash());
  for (int k = 0; k < 1000; ++k) {
    a->Step();
    b->Step();
  }
  EXPECT_EQ(b->StateHash(), a->StateHash());
  const auto ba = a->TakeBondBreaks(), bb = b->TakeBondBreaks();
  ASSERT_EQ(ba.size(), bb.size());
  for (size_t k = 0; k < ba.size(); ++k) EXPECT_EQ(ba[k].stress, bb[k].stress);
  ASSERT_EQ(a->bonds().size(), b->bonds().size());
  for (size_t k = 0; k < a->bonds().size(); ++k) {
    EXPECT_EQ(a->bonds()[k].fn, b->bonds()[k].fn);
    EXPECT_EQ(a->bonds()[k].intact, b->bonds()[k].intact);
  }
  EXPECT_TRUE(a->SaveState() == b->SaveState());
}

// The bond calls' checks and bookkeeping: AddBonds refuses unknown, equal, reversed, repeated and
// clump-internal pairs and bad values, adding nothing; removing a sphere removes its bonds;
// PairsWithinGap is the brute-force O(N^2) list of pairs closer than the gap.
TEST(BondTest, AddBondsChecksAndPairsWithinGap) {
  auto sys = MakeSystem(1e-6);
  std::vector<int64_t> ids;
  for (int k = 0; k < 40; ++k)
    ids.push_back(
        sys->AddParticle({(k % 4) * 2.1 * kR, ((k / 4) % 5) * 2.05 * kR, (k / 20) * 2.3 * kR}, {},
                         {}, kR * (1 + 0.01 * (k % 3)), 0));
  const BondParams params = Params();
  const Bond good = MakeBond(ids[0], kR, ids[1], kR, 2.1 * kR, params);
  EXPECT_THROW(MakeBond(0, kR, 1, kR, 2 * kR, BondParams{}), std::invalid_argument);
  Bond bad = good;
  bad.b = 1000;
  EXPECT_THROW(sys->AddBonds({good, bad}), std::invalid_argument);
  bad = good;
  bad.b = bad.a;
  EXPECT_THROW(sys->AddBonds({bad}), std::invalid_argument);
  bad = good;
  std::swap(bad.a, bad.b);
  EXPECT_THROW(sys->AddBonds({bad}), std::invalid_argument);
  bad = good;
  bad.kn = 0;
  EXPECT_THROW(sys->AddBonds({bad}), std::invalid_argument);
  EXPECT_THROW(sys->AddBonds({good, good}), std::invalid_argument);
  EXPECT_TRUE(sys->bonds().empty());
  sys->AddBonds({good});
  EXPECT_THROW(sys->AddBonds({good}), std::invalid_argument);
  EXPECT_NEAR(sys->bonds()[0].normal.x, 1.0, 1e-15);
  // Brute force.
  const double gap = 0.08 * kR;
  std::vector<std::pair<int64_t, int64_t>> brute;
  const Particles& p = sys->particles();
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = 0; j < p.size(); ++j)
      if (p.id[i] < p.id[j] && Norm(p.x[j] - p.x[i]) < p.radius[i] + p.radius[j] + gap)
        brute.emplace_back(p.id[i], p.id[j]);
  std::sort(brute.begin(), brute.end());
  const auto found = sys->PairsWithinGap(gap);
  EXPECT_EQ(found, brute);
  EXPECT_GT(found.size(), 20u);
  // Removing a sphere takes its bonds with it.
  std::vector<Bond> more;
  for (const auto& [a, b] : found)
    if (a != ids[0] || b != ids[1]) more.push_back(MakeBond(a, kR, b, kR, 2.1 * kR, params));
  sys->AddBonds(more);
  const size_t before = sys->bonds().size();
  size_t of_five = 0;
  for (const Bond& b : sys->bonds()) of_five += b.a == ids[5] || b.b == ids[5];
  sys->RemoveParticles({ids[5]});
  EXPECT_EQ(sys->bonds().size(), before - of_five);
  EXPECT_GT(of_five, 0u);
  test::StepOk(*sys, 5);
}

// Sleeping: two bonded spheres at rest fall asleep (the bond frozen); when one is woken and set
// moving away faster than wake_speed, the bond wakes the other within the step, and then pulls
// it after the first (in tension).
TEST(BondTest, AFastAwakeEndWakesTheOther) {
  auto sys = MakeSystem(1e-6);
  SleepConfig sc;
  sc.enabled = true;
  sc.check_every = 1;
  sc.quiet_checks = 1;
  sys->set_sleep(sc);
  const int64_t a = sys->AddParticle({0, 0, 0}, {}, {}, kR, 0);
  const int64_t b = sys->AddParticle({2 * kR, 0, 0}, {}, {}, kR, 0);
  sys->AddBonds({MakeBond(a, kR, b, kR, 2 * kR, Params())});
  test::StepOk(*sys, 5);
  ASSERT_EQ(sys->awake_count(), 0);
  Particles& p = sys->mutable_particles();
  p.awake[IndexOf(*sys, a)] = 1;
  p.v[IndexOf(*sys, a)] = {-0.01, 0, 0};
  sys->Touch();
  test::StepOk(*sys);
  EXPECT_EQ(sys->awake_count(), 2);
  sc.check_every = 1000;  // no sleep check while b picks up speed
  sys->set_sleep(sc);
  test::StepOk(*sys, 20);
  EXPECT_LT(sys->particles().v[IndexOf(*sys, b)].x, 0.0);  // pulled after a
  EXPECT_GT(sys->bonds()[0].fn, 0.0);                      // in tension
}

// A clump's two spheres cannot be bonded to each other; a clump's sphere to a free one can, and
// the clump then feels the bond (its body moves).
TEST(BondTest, ClumpSpheresBond) {
  auto sys = MakeSystem(1e-6);
  ClumpTemplate t;
  t.name = "pair";
  t.centers = {{-kR, 0, 0}, {kR, 0, 0}};
  t.radii = {kR, kR};
  const int shape = sys->AddClumpTemplate(t);
  sys->AddClump(shape, Pose{}, {}, {}, 0);
  const int64_t free_id = sys->AddParticle({3 * kR, 0, 0}, {0.01, 0, 0}, {}, kR, 0);
  EXPECT_THROW(sys->AddBonds({MakeBond(0, kR, 1, kR, 2 * kR, Params())}), std::invalid_argument);
  sys->AddBonds({MakeBond(1, kR, free_id, kR, 2 * kR, Params())});
  test::StepOk(*sys, 100);
  EXPECT_GT(sys->clumps().v[0].x, 0.0);  // pulled along by the bond
  EXPECT_TRUE(sys->bonds()[0].intact);
}

}  // namespace
}  // namespace dem

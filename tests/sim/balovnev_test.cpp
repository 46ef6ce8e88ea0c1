// sim/studies/balovnev.h: Balovnev's excavation force (FACTS.md section 7) against values computed by
// hand, its limits and its refusals.
#include "sim/studies/balovnev.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// The lander plugin's soil (FACTS.md section 7): phi 44 deg, delta 28 deg, c 0, rho 1700 kg/m3,
// g 1.315 m/s2, q = g x 1 kg/m2; the scoop of BalovnevTool's defaults.
BalovnevSoil PluginSoil() {
  BalovnevSoil s;
  s.friction_angle = 44 * kDeg;
  s.tool_friction_angle = 28 * kDeg;
  s.cohesion = 0;
  s.unit_weight = 1700 * 1.315;  // 2235.5 N/m^3
  s.surcharge = 1.315;           // Pa
  return s;
}

// The hand computation (30 significant digits, mpmath; the formulas of sim/studies/balovnev.h):
//   sin 44 = 0.694658370458997, K = (1 - sin phi)/(1 + sin phi) = 0.180178869596178
//   psi = asin(sin 28 / sin 44) = 0.742091385594528 rad, x* = (pi - delta - psi)/2 = 54.7406 deg
//   beta = 10 deg and alpha_e = 30 deg lie below x*: A_I; pi/2 above: A_II
//   A_I(10) = (1 - sin44 cos20)/(1 - sin44) = 1.13720050500316,  A_II(10) = 0.892735831535437
//   A_I(30) = (1 - sin44 cos60)/(1 - sin44) = 2.13751009238934,  A_II(30) = 1.75192184688878
//   A_II(90) = cos28 (cos28 + sqrt(sin^2 44 - sin^2 28))/(1 - sin44) exp((28 deg + psi) tan44)
//            = 13.2400618767841
// d = 0.01 m, b = 0: P(d) = 2235.5 x 0.01 / 2 + 1.315 = 12.4925 Pa, P(e) = 1.76210 Pa
//   F_1 = 0.085 x 0.01 x 1.13720 x (1 + tan28/tan10) x 12.4925            = 0.0484888796248625
//   F_2 = 0.085 x 0.0004 x 2.13751 x (1 + tan28/tan30) x (1.76210 + 0.01 x 2235.5 x K)
//                                                                         = 0.000808315867505991
//   F_3 = 0.01 x 13.2401 x (2 x 0.0016 + 4 x 0.1225 x tan28) x 12.4925    = 0.436225910828254
//   F_h = 0.485523106320622, F_v = F_h / tan(38 deg) = 0.621441237171471
//   plugin branch (A_II everywhere): F_h = 0.474953609676435, F_v = 0.607912898385251
// d = 0.03 m, b = 1 (buried): P(d) = 34.8475 Pa
//   F_1 = 0.085 x 0.03 x 1.13720 x (1 + tan28/tan10) x (34.8475 + (0.03 - 0.0026 sin10) 2235.5 K)
//       = 0.544364192901421
//   F_2 = 0.085 x 0.0004 x 2.13751 x (1 + tan28/tan30) x (1.76210 + 0.03 x 2235.5 x K)
//       = 0.00193294976929017
//   F_3 = 0.03 x 13.2401 x (0.0032 + 0.49 tan28) x (34.8475 + (0.03 - 0.1225 sin10) 2235.5 K)
//       = 4.01880496042802
//   F_h = 4.56510210309873, F_v = 5.84306423696824
//   plugin branch: F_h = 4.44773111926777, F_v = 5.69283622835154
// Tolerance: relative 1e-9 (the double evaluation against 30 digits).
TEST(BalovnevTest, MatchesHandComputedValuesAtTwoDepths) {
  struct Case {
    double depth;
    bool buried;
    double blade, edge, sides, horizontal, vertical;  // A split at x*
    double plugin_horizontal, plugin_vertical;        // A_II everywhere
  };
  const Case cases[] = {
      {0.01, false, 0.0484888796248625, 0.000808315867505991, 0.436225910828254, 0.485523106320622,
       0.621441237171471, 0.474953609676435, 0.607912898385251},
      {0.03, true, 0.544364192901421, 0.00193294976929017, 4.01880496042802, 4.56510210309873,
       5.84306423696824, 4.44773111926777, 5.69283622835154},
  };
  const BalovnevTool tool;
  const BalovnevSoil soil = PluginSoil();
  const double rel = 1e-9;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.depth);
    const BalovnevForce f = Balovnev(c.depth, tool, soil, c.buried, BalovnevBranch::kSplit);
    EXPECT_NEAR(f.blade, c.blade, rel * c.blade);
    EXPECT_NEAR(f.edge, c.edge, rel * c.edge);
    EXPECT_NEAR(f.sides, c.sides, rel * c.sides);
    EXPECT_NEAR(f.horizontal, c.horizontal, rel * c.horizontal);
    EXPECT_NEAR(f.vertical, c.vertical, rel * c.vertical);
    const BalovnevForce p = Balovnev(c.depth, tool, soil, c.buried, BalovnevBranch::kPlugin);
    EXPECT_NEAR(p.horizontal, c.plugin_horizontal, rel * c.plugin_horizontal);
    EXPECT_NEAR(p.vertical, c.plugin_vertical, rel * c.plugin_vertical);
    // FACTS: the plugin's branch gives about 2.2% less force (unburied; 2.6% buried at 30 mm).
    EXPECT_NEAR(p.horizontal / f.horizontal, c.buried ? 0.974 : 0.978, 0.001);
  }
}

// A's branches: A_I(10 deg), A_II(90 deg) by hand (above); the two meet at x* (A_I(x*) = A_II(x*)
// exactly in closed form: sin phi cos(delta + psi) = cos delta sqrt(sin^2 phi - sin^2 delta) -
// sin^2 delta), relative 1e-12; the split rule takes A_I at x* and A_II just above.
TEST(BalovnevTest, BranchesMeetAtTheStatedAngle) {
  const BalovnevSoil soil = PluginSoil();
  const double x_star = BalovnevBranchAngle(soil);
  EXPECT_NEAR(x_star, 0.955404538718427, 1e-12);
  EXPECT_NEAR(BalovnevA(10 * kDeg, soil, BalovnevBranch::kSplit), 1.13720050500316, 1e-12);
  EXPECT_NEAR(BalovnevA(10 * kDeg, soil, BalovnevBranch::kPlugin), 0.892735831535437, 1e-12);
  EXPECT_NEAR(BalovnevA(kPi / 2, soil, BalovnevBranch::kSplit), 13.2400618767841, 1e-11);
  const double a_i = BalovnevA(x_star, soil, BalovnevBranch::kSplit);
  const double a_ii = BalovnevA(x_star, soil, BalovnevBranch::kPlugin);
  EXPECT_NEAR(a_i, a_ii, 1e-12 * a_ii);
  EXPECT_NEAR(BalovnevA(x_star + 1e-9, soil, BalovnevBranch::kSplit), a_ii, 1e-7 * a_ii);
}

// Limits: zero depth gives zero force (by definition), and the force grows with depth. Just above
// zero the blunt-edge term alone is left, F_2(0+) = w e A(alpha_e) (1 + tan delta cot alpha_e) P(e)
// (the jump the definition removes): by hand, F_2(0.01) x P(e) / (P(e) + 0.01 gamma K) with
// P(e) = 1.7621 Pa and 0.01 gamma K = 4.02789862982255 Pa, relative 1e-9 at d = 1e-15 m.
TEST(BalovnevTest, ZeroDepthGivesZeroForceAndForceGrowsWithDepth) {
  const BalovnevTool tool;
  const BalovnevSoil soil = PluginSoil();
  for (const bool buried : {false, true}) {
    const BalovnevForce zero = Balovnev(0, tool, soil, buried, BalovnevBranch::kSplit);
    EXPECT_EQ(zero.horizontal, 0.0);
    EXPECT_EQ(zero.vertical, 0.0);
    EXPECT_EQ(zero.blade + zero.edge + zero.sides, 0.0);
  }
  double last = 0;
  for (const double d : {0.001, 0.005, 0.01, 0.02, 0.05}) {
    const double f = Balovnev(d, tool, soil, false, BalovnevBranch::kSplit).horizontal;
    EXPECT_GT(f, last) << d;
    last = f;
  }
  const double p_e = 1.7621;
  const double edge0 = 0.000808315867505991 * p_e / (p_e + 4.02789862982255);
  const BalovnevForce tiny = Balovnev(1e-15, tool, soil, false, BalovnevBranch::kSplit);
  EXPECT_NEAR(tiny.edge, edge0, 1e-9 * edge0);
  EXPECT_NEAR(tiny.horizontal, edge0, 1e-9 * edge0);
}

// The lander plugin's variant (BalovnevLander; FACTS.md section 7), by hand from the values above
// (A_II(10) = 0.892735831535437, A_II(30) = 1.75192184688878, A_II(90) = 13.2400618767841,
// K = 0.180178869596178; its own gamma = 1700 x 1.315 = 2235.5 N/m^3, q = 1.315 x 1 = 1.315 Pa,
// b = 0, A_II everywhere; 1 + tan28/tan10 = 4.01547403310101, 1 + tan28/tan30 = 1.92094775050125,
// 2 s + 4 l_s tan28 = 0.263737621514125; caps F_h <= 40 N, then F_v = min(F_h cot 38, 30 N),
// cot 38 = 1.27994163219308, so the F_v cap binds from F_h = 23.4386 N):
// d = 0.02 m: P(d) = 2235.5 x 0.02 / 2 + 1.315 = 23.67 Pa, P(e) = 1.7621 Pa
//   F_1 = 0.085 x 0.02 x 0.892736 x 4.015474 x 23.67                  = 0.144247059
//   F_2 = 0.085 x 0.0004 x 1.751922 x 1.920948 x (1.7621 + 0.02 x 2235.5 K) = 0.00112338257
//   F_3 = 0.02 x 13.240062 x 0.263738 x 23.67                         = 1.65306661
//   F_h = 1.79843705 (under 40), F_v = 1.79843705 x 1.279942 = 2.30189445 (under 30)
// d = 0.08 m: P(d) = 90.735 Pa; F_1 = 2.21178824, F_2 = 0.00388866173, F_3 = 25.3470213
//   F_h = 27.5626982 (under 40), F_h cot 38 = 35.278645 -> F_v = 30 (capped)
// d = 0.25 m: P(d) = 280.7525 Pa; F_1 = 21.3866299, F_2 = 0.0117236193, F_3 = 245.090084
//   F_h = 266.488438 -> 40 (capped), 40 cot 38 = 51.2 -> F_v = 30 (capped)
// The soil's unit weight and surcharge are the plugin's own, whatever the caller's (a DEM bed's
// gamma here). Tolerance: relative 1e-8 (hand values to 9 digits).
TEST(BalovnevTest, LanderPluginVariantMatchesHandValuesWithItsCaps) {
  const BalovnevTool tool;
  BalovnevSoil soil = PluginSoil();
  soil.unit_weight = 1326.6 * 1.3;  // ignored by the variant
  soil.surcharge = 7;               // ignored
  struct Case {
    double depth, blade, edge, sides, horizontal, vertical;
  };
  const Case cases[] = {{0.02, 0.144247059, 0.00112338257, 1.65306661, 1.79843705, 2.30189445},
                        {0.08, 2.21178824, 0.00388866173, 25.3470213, 27.5626982, 30},
                        {0.25, 21.3866299, 0.0117236193, 245.090084, 40, 30}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.depth);
    const BalovnevForce f = BalovnevLander(c.depth, tool, soil);
    EXPECT_NEAR(f.blade, c.blade, 1e-8 * c.blade);
    EXPECT_NEAR(f.edge, c.edge, 1e-8 * c.edge);
    EXPECT_NEAR(f.sides, c.sides, 1e-8 * c.sides);
    EXPECT_NEAR(f.horizontal, c.horizontal, 1e-8 * c.horizontal);
    EXPECT_NEAR(f.vertical, c.vertical, 1e-8 * c.vertical);
  }
  EXPECT_EQ(BalovnevLander(0, tool, soil).horizontal, 0.0);
  EXPECT_STREQ(BalovnevModelName(BalovnevModel::kLander), "lander");
  EXPECT_STREQ(BalovnevModelName(BalovnevModel::kTextbook), "textbook");
}

// Bad inputs: one std::invalid_argument naming the value.
TEST(BalovnevTest, RefusesInputsOutsideTheModel) {
  const BalovnevTool tool;
  const BalovnevSoil soil = PluginSoil();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto refuses = [](auto&& call, const char* word) {
    try {
      call();
      ADD_FAILURE() << "accepted: " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  refuses([&] { Balovnev(-0.01, tool, soil, false, BalovnevBranch::kSplit); }, "depth");
  refuses([&] { Balovnev(nan, tool, soil, false, BalovnevBranch::kSplit); }, "depth");
  BalovnevSoil s = soil;
  s.tool_friction_angle = 50 * kDeg;  // delta > phi: psi undefined
  refuses([&] { Balovnev(0.01, tool, s, false, BalovnevBranch::kSplit); }, "delta");
  s = soil;
  s.friction_angle = 0;
  refuses([&] { Balovnev(0.01, tool, s, false, BalovnevBranch::kSplit); }, "phi");
  s = soil;
  s.unit_weight = 0;
  refuses([&] { Balovnev(0.01, tool, s, false, BalovnevBranch::kSplit); }, "gamma");
  s = soil;
  s.cohesion = -1;
  refuses([&] { Balovnev(0.01, tool, s, false, BalovnevBranch::kSplit); }, "cohesion");
  BalovnevTool t = tool;
  t.rake = 0;  // cot beta infinite
  refuses([&] { Balovnev(0.01, t, soil, false, BalovnevBranch::kSplit); }, "beta");
  t = tool;
  t.width = -0.085;
  refuses([&] { Balovnev(0.01, t, soil, false, BalovnevBranch::kSplit); }, "width");
  refuses([&] { BalovnevA(2.0, soil, BalovnevBranch::kSplit); }, "A(x)");
}

}  // namespace
}  // namespace sim

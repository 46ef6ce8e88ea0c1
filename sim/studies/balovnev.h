// Balovnev's analytical excavation force on a bucket (FACTS.md section 7): the baseline the
// reference study's DEM improves on (paper section 1, its ref. [9]: V. I. Balovnev, "New Methods
// for Calculating Resistance to Cutting of Soil", 1983), in two named variants (issue 40):
//   textbook  Balovnev(): the formula below with the caller's soil (gamma from the DEM bed, q, b)
//             and A split at x* (kSplit; kPlugin for the plugin's branch alone);
//   lander    BalovnevLander(): the OceanWATERS lander simulator's Balovnev plugin, with its own
//             constants (rho_bulk 1700 kg/m^3, g 1.315 m/s^2, q = g x 1 kg/m^2, b = 0), its
//             branch rule (A_II at these angles) and its caps (F_h <= 40 N, then
//             F_v = min(F_h cot(beta + delta), 30 N) from the capped F_h), FACTS.md section 7.
// Pure functions, SI units, angles in rad. Not ground truth: a quasi-static wedge model with no
// velocity term, for comparison with the DEM (`scoopsim study balovnev`, sim/studies/commands.h).
//
// Symbols: d cutting depth; w blade width; beta rake angle from horizontal; phi internal friction
// angle; delta soil-tool friction angle; c cohesion; gamma = rho_bulk g; q surcharge; l blade
// length from the tip; l_s side-plate length; s side-plate thickness; e, alpha_e blunt edge
// thickness and angle; b = 1 if the bucket is buried, else 0; K = (1 - sin phi) / (1 + sin phi);
// P(h) = gamma h / 2 + c cot phi + q.
//   F_1 = w d A(beta) (1 + cot beta tan delta) [P(d) + b (d - l sin beta) gamma K]      blade
//   F_2 = w e A(alpha_e) (1 + tan delta cot alpha_e) [P(e) + d gamma K]               blunt edge
//   F_3 = d A(pi/2) (2 s + 4 l_s tan delta) [P(d) + b (d - l_s sin beta) gamma K]  side plates
//   F_h = F_1 + F_2 + F_3 (horizontal, against the motion);  F_v = F_h cot(beta + delta)
//   (vertical, downward on the tool: the soil's reaction on a low-rake blade leans back by
//   beta + delta from the vertical; the plugin applies it as +z of the l_scoop frame, which points
//   down when the scoop digs level).
//   A_I(x)  = (1 - sin phi cos 2x) / (1 - sin phi)
//   A_II(x) = cos delta (cos delta + sqrt(sin^2 phi - sin^2 delta)) / (1 - sin phi)
//             exp((2x - pi + delta + psi) tan phi),   psi = asin(sin delta / sin phi).
// The branch rule for A: public implementations disagree. The two branches meet at
// x* = (pi - delta - psi) / 2 (A_I(x*) = A_II(x*), tested), so kSplit takes A_I for x <= x* and
// A_II above; kPlugin takes A_II for every x, as the lander plugin's branch test does at these
// angles (2.2% less force at FACTS's values). At d = 0 the blunt-edge term F_2 alone would not
// vanish: the force is defined as zero there (no cut, no force).
#pragma once

namespace sim {

// Where A(x) switches from A_I to A_II (see above).
enum class BalovnevBranch {
  kSplit,   // A_I for x <= x*, A_II above (FACTS.md section 7)
  kPlugin,  // A_II always (the OceanWATERS Balovnev plugin at these angles)
};

// The bucket. Defaults: the scoop values used with the model (FACTS.md section 7).
struct BalovnevTool {
  double width = 0.085;                    // w [m]
  double blade_length = 0.0026;            // l, from the tip [m]
  double side_length = 0.1225;             // l_s [m]
  double side_thickness = 0.0016;          // s [m]
  double edge_thickness = 0.0004;          // e [m]
  double edge_angle = 0.5235987755982988;  // alpha_e = 30 deg [rad]
  double rake = 0.17453292519943295;       // beta = 10 deg [rad]
};

// The soil. Defaults: FACTS.md section 7's soil angles, no cohesion, no surcharge; gamma has no
// default that fits a DEM bed (its bulk density times g): set it.
struct BalovnevSoil {
  double friction_angle = 0.767944870877505;        // phi = 44 deg [rad]
  double tool_friction_angle = 0.4886921905584123;  // delta = 28 deg [rad]
  double cohesion = 0;                              // c [Pa]
  double unit_weight = 0;                           // gamma = rho_bulk g [N/m^3]
  double surcharge = 0;                             // q [Pa]
};

struct BalovnevForce {
  double horizontal = 0;                  // F_h, against the motion [N]
  double vertical = 0;                    // F_v, downward on the tool [N]
  double blade = 0, edge = 0, sides = 0;  // F_1, F_2, F_3 [N]
};

// The two variants, by name ("textbook", "lander").
enum class BalovnevModel { kTextbook, kLander };
const char* BalovnevModelName(BalovnevModel model);

// The lander plugin's own constants (FACTS.md section 7, checked in its source).
struct BalovnevLanderConstants {
  double bulk_density = 1700;  // rho_bulk [kg/m^3]
  double gravity = 1.315;      // g [m/s^2]
  double surcharge_mass = 1;   // q = g x this [kg/m^2]
  double max_horizontal = 40;  // F_h cap [N]
  double max_vertical = 30;    // F_v cap [N]
};

// x* = (pi - delta - psi) / 2 [rad], where A_I and A_II meet.
double BalovnevBranchAngle(const BalovnevSoil& soil);
// A(x) for x in (0, pi/2], by `branch`.
double BalovnevA(double x, const BalovnevSoil& soil, BalovnevBranch branch);
// The force at cutting depth `depth` >= 0 [m] (zero at 0); `buried` sets b.
// Throws std::invalid_argument (one line naming the value and what was expected) for a negative or
// non-finite depth, or a tool or soil outside the model's domain: lengths and w > 0 (l_s, s, e
// >= 0), beta and alpha_e in (0, pi/2], phi in (0, pi/2), delta in [0, phi], c, q >= 0, gamma > 0.
BalovnevForce Balovnev(double depth, const BalovnevTool& tool, const BalovnevSoil& soil,
                       bool buried, BalovnevBranch branch);
// The lander plugin's variant at cutting depth `depth` (its plugin takes a moving maximum of the
// trench depth; here the caller's depth): Balovnev() with the soil's phi, delta and c, but
// gamma = rho_bulk g and q = g x surcharge_mass from `lander`, b = 0 and A_II (kPlugin); then
// F_h = min(F_h, max_horizontal) and F_v = min(F_h cot(beta + delta), max_vertical) with the
// capped F_h. blade, edge and sides are the terms before the caps. soil.unit_weight and
// soil.surcharge are not used. Throws as Balovnev().
BalovnevForce BalovnevLander(double depth, const BalovnevTool& tool, const BalovnevSoil& soil,
                             const BalovnevLanderConstants& lander = {});

}  // namespace sim

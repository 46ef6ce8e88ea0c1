#include "sim/studies/balovnev.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Num(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

void Require(bool ok, const char* what, const char* expected, double got) {
  if (!ok)
    throw std::invalid_argument(std::string("Balovnev: ") + what + ": expected " + expected +
                                ", got " + Num(got));
}

void CheckSoil(const BalovnevSoil& s) {
  Require(std::isfinite(s.friction_angle) && s.friction_angle > 0 && s.friction_angle < kPi / 2,
          "friction angle phi [rad]", "a value in (0, pi/2)", s.friction_angle);
  Require(std::isfinite(s.tool_friction_angle) && s.tool_friction_angle >= 0 &&
              s.tool_friction_angle <= s.friction_angle,
          "soil-tool friction angle delta [rad]", "a value in [0, phi]", s.tool_friction_angle);
  Require(std::isfinite(s.cohesion) && s.cohesion >= 0, "cohesion c [Pa]", ">= 0", s.cohesion);
  Require(std::isfinite(s.unit_weight) && s.unit_weight > 0, "unit weight gamma [N/m^3]", "> 0",
          s.unit_weight);
  Require(std::isfinite(s.surcharge) && s.surcharge >= 0, "surcharge q [Pa]", ">= 0", s.surcharge);
}

void CheckTool(const BalovnevTool& t) {
  Require(std::isfinite(t.width) && t.width > 0, "width w [m]", "> 0", t.width);
  Require(std::isfinite(t.blade_length) && t.blade_length >= 0, "blade length l [m]", ">= 0",
          t.blade_length);
  Require(std::isfinite(t.side_length) && t.side_length >= 0, "side-plate length l_s [m]", ">= 0",
          t.side_length);
  Require(std::isfinite(t.side_thickness) && t.side_thickness >= 0, "side-plate thickness s [m]",
          ">= 0", t.side_thickness);
  Require(std::isfinite(t.edge_thickness) && t.edge_thickness >= 0, "edge thickness e [m]", ">= 0",
          t.edge_thickness);
  Require(std::isfinite(t.edge_angle) && t.edge_angle > 0 && t.edge_angle <= kPi / 2,
          "edge angle alpha_e [rad]", "a value in (0, pi/2]", t.edge_angle);
  Require(std::isfinite(t.rake) && t.rake > 0 && t.rake <= kPi / 2, "rake angle beta [rad]",
          "a value in (0, pi/2]", t.rake);
}

// psi = asin(sin delta / sin phi) (delta <= phi keeps the argument in [0, 1]).
double Psi(const BalovnevSoil& s) {
  return std::asin(std::sin(s.tool_friction_angle) / std::sin(s.friction_angle));
}

// P(h) = gamma h / 2 + c cot phi + q [Pa].
double P(double h, const BalovnevSoil& s) {
  return s.unit_weight * h / 2 + s.cohesion / std::tan(s.friction_angle) + s.surcharge;
}

}  // namespace

double BalovnevBranchAngle(const BalovnevSoil& soil) {
  CheckSoil(soil);
  return (kPi - soil.tool_friction_angle - Psi(soil)) / 2;
}

double BalovnevA(double x, const BalovnevSoil& soil, BalovnevBranch branch) {
  CheckSoil(soil);
  Require(std::isfinite(x) && x > 0 && x <= kPi / 2, "angle x of A(x) [rad]",
          "a value in (0, pi/2]", x);
  const double phi = soil.friction_angle, delta = soil.tool_friction_angle;
  const double sin_phi = std::sin(phi);
  const double psi = Psi(soil);
  if (branch == BalovnevBranch::kSplit && x <= (kPi - delta - psi) / 2)
    return (1 - sin_phi * std::cos(2 * x)) / (1 - sin_phi);  // A_I
  const double sin_delta = std::sin(delta);
  return std::cos(delta) *
         (std::cos(delta) + std::sqrt(sin_phi * sin_phi - sin_delta * sin_delta)) / (1 - sin_phi) *
         std::exp((2 * x - kPi + delta + psi) * std::tan(phi));  // A_II
}

BalovnevForce Balovnev(double depth, const BalovnevTool& tool, const BalovnevSoil& soil,
                       bool buried, BalovnevBranch branch) {
  CheckTool(tool);
  CheckSoil(soil);
  Require(std::isfinite(depth) && depth >= 0, "cutting depth d [m]", ">= 0", depth);
  BalovnevForce f;
  if (depth == 0) return f;  // no cut, no force (F_2 alone would not vanish)
  const double d = depth, gamma = soil.unit_weight;
  const double sin_phi = std::sin(soil.friction_angle);
  const double k = (1 - sin_phi) / (1 + sin_phi);
  const double tan_delta = std::tan(soil.tool_friction_angle);
  const double b = buried ? 1.0 : 0.0;
  const double beta = tool.rake;
  f.blade = tool.width * d * BalovnevA(beta, soil, branch) * (1 + tan_delta / std::tan(beta)) *
            (P(d, soil) + b * (d - tool.blade_length * std::sin(beta)) * gamma * k);
  f.edge = tool.width * tool.edge_thickness * BalovnevA(tool.edge_angle, soil, branch) *
           (1 + tan_delta / std::tan(tool.edge_angle)) *
           (P(tool.edge_thickness, soil) + d * gamma * k);
  f.sides = d * BalovnevA(kPi / 2, soil, branch) *
            (2 * tool.side_thickness + 4 * tool.side_length * tan_delta) *
            (P(d, soil) + b * (d - tool.side_length * std::sin(beta)) * gamma * k);
  f.horizontal = f.blade + f.edge + f.sides;
  f.vertical = f.horizontal / std::tan(beta + soil.tool_friction_angle);
  return f;
}

const char* BalovnevModelName(BalovnevModel model) {
  return model == BalovnevModel::kLander ? "lander" : "textbook";
}

BalovnevForce BalovnevLander(double depth, const BalovnevTool& tool, const BalovnevSoil& soil,
                             const BalovnevLanderConstants& lander) {
  BalovnevSoil own = soil;
  own.unit_weight = lander.bulk_density * lander.gravity;
  own.surcharge = lander.gravity * lander.surcharge_mass;
  BalovnevForce f = Balovnev(depth, tool, own, false, BalovnevBranch::kPlugin);
  f.horizontal = std::min(f.horizontal, lander.max_horizontal);
  f.vertical =
      std::min(f.horizontal / std::tan(tool.rake + soil.tool_friction_angle), lander.max_vertical);
  return f;
}

}  // namespace sim

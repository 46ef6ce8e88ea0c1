// Hertz-Mindlin (no-slip) contact law with rolling friction, as EDEM and LIGGGHTS define it.
//
// Normal (Hertz 1882; EDEM theory guide; Tsuji et al. 1992 damping form):
//   F_n = 4/3 E* sqrt(R*) delta^(3/2),           S_n = 2 E* sqrt(R* delta)
//   F_n^d = -2 sqrt(5/6) beta sqrt(S_n m*) v_n
// Tangential (Mindlin 1949, no-slip):
//   S_t = 8 G* sqrt(R* delta),   F_t = -S_t xi - 2 sqrt(5/6) beta sqrt(S_t m*) v_t,  |F_t| <= mu
//   F_n with xi the tangential spring displacement (contact history).
// Rolling friction (constant directional torque, "CDT"/EPSD type 1, Ai et al. 2011):
//   M_r = -mu_r R* F_n w_rel / |w_rel|
// Effective values: 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2, 1/G* = (2-nu1)/G1 + (2-nu2)/G2,
// 1/R* = 1/R1 + 1/R2, 1/m* = 1/m1 + 1/m2 (a wall has R, m = infinity).
//
// Damping: with this damping form the coefficient of restitution does not depend on the impact
// speed, but EDEM's closed form beta = ln e / sqrt(ln^2 e + pi^2) (exact only for a linear spring)
// does not give e for the Hertz spring. We instead solve the nondimensional Hertz impact
//   x'' = -x^(3/2) - zeta x^(1/4) x',  x(0) = 0, x'(0) = 1,  zeta = sqrt(5) beta
// (total normal force clamped at >= 0: non-cohesive contact) and pick beta so that the rebound
// speed |x'(end)| equals e to 1e-9. A binary collision then has exactly the material's e.
// Public header of the dem module.
#pragma once

#include <algorithm>
#include <cmath>

#include "dem/material.h"
#include "dem/vec3.h"

namespace dem {

// Constants of one material pair, precomputed once.
struct PairConstants {
  double e_star = 0;            // effective Young's modulus E* [Pa]
  double g_star = 0;            // effective shear modulus G* [Pa]
  double damp = 0;              // 2 sqrt(5/6) beta (beta > 0) [-]
  double tangential_ratio = 0;  // sqrt(S_t / S_n) = sqrt(4 G* / E*) [-]
  double friction = 0;          // mu_s [-]
  double rolling_friction = 0;  // mu_r [-]
};

PairConstants MakePairConstants(const Material& a, const Material& b, const Interaction& i);

// Coefficient of restitution of the nondimensional Hertz impact with damping parameter beta.
double RestitutionForBeta(double beta);
// Inverse of RestitutionForBeta on (0, 1]: the beta that gives restitution e.
double BetaForRestitution(double e);

// Closed form of the elastic Hertz normal force [N] (for tests and energy bookkeeping).
inline double HertzForce(double e_star, double r_star, double delta) {
  return 4.0 / 3.0 * e_star * std::sqrt(r_star) * delta * std::sqrt(delta);
}

// Result of one contact evaluation, as felt by side a.
struct ContactForce {
  double fn = 0;  // normal force magnitude (>= 0) [N]; force on a is -fn * n
  Vec3 ft;        // tangential force on a [N]
  Vec3 mr;        // rolling-friction torque on a [N m]
};

// Evaluates one contact. n points from a to b (unit); delta > 0 is the overlap [m]; v_rel is the
// velocity of b's contact point minus a's [m/s]; w_rel = w_a - w_b [rad/s]; inv_inertia_sum is
// 1/I_a + 1/I_b (the rolling torque is limited so that it cannot reverse w_rel within one step);
// shear is the tangential history (updated in place).
inline ContactForce EvaluateContact(const PairConstants& c, const Vec3& n, double delta,
                                    double r_star, double m_star, const Vec3& v_rel,
                                    const Vec3& w_rel, double inv_inertia_sum, double dt,
                                    Vec3& shear) {
  ContactForce out;
  const double vn = Dot(v_rel, n);
  const Vec3 vt = v_rel - vn * n;
  const double s = std::sqrt(r_star * delta);              // sqrt(R* delta) [m]
  const double sn = 2.0 * c.e_star * s;                    // normal stiffness S_n [N/m]
  const double gamma_n = c.damp * std::sqrt(sn * m_star);  // [kg/s]
  const double fn = std::max(0.0, 2.0 / 3.0 * sn * delta - gamma_n * vn);
  out.fn = fn;

  // Tangential spring: rotate the history into the current tangent plane keeping its length
  // (LIGGGHTS convention), then add this step's tangential displacement.
  const double xi_n = Dot(shear, n);
  if (xi_n != 0.0) {
    shear -= xi_n * n;
    const double new2 = Norm2(shear);
    if (new2 > 0.0) {
      // Rescale to the old length: sqrt(old2 / new2) = sqrt(1 + q), q = xi_n^2 / new2. The normal
      // part is tiny from one step to the next, so a two-term series (error < q^3 / 16 < 1e-13)
      // saves the square root.
      const double q = xi_n * xi_n / new2;
      shear *= q < 1e-4 ? 1.0 + q * (0.5 - 0.125 * q) : std::sqrt(1.0 + q);
    }
  }
  shear += dt * vt;
  const double st = 4.0 * c.g_star / c.e_star * sn;  // S_t = 8 G* s
  const double gamma_t = c.tangential_ratio * gamma_n;
  Vec3 ft = st * shear + gamma_t * vt;
  const double ft2 = Norm2(ft);
  const double cap = c.friction * fn;
  if (ft2 > cap * cap) {
    // Sliding: Coulomb cap; the spring then carries the whole friction force.
    ft *= cap / std::sqrt(ft2);
    shear = (1.0 / st) * ft;
  }
  out.ft = ft;

  // Rolling friction, a constant torque against the relative rotation.
  const double w2 = Norm2(w_rel);
  if (c.rolling_friction > 0.0 && w2 > 0.0) {
    const double w = std::sqrt(w2);
    const double m = std::min(c.rolling_friction * r_star * fn, w / (dt * inv_inertia_sum));
    out.mr = (-m / w) * w_rel;
  }
  return out;
}

}  // namespace dem

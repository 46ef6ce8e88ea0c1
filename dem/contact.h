// Hertz-Mindlin (no-slip) contact law with rolling friction, as EDEM and LIGGGHTS define it.
//
// Normal (Hertz 1882; EDEM theory guide; Tsuji et al. 1992 damping form):
//   F_n = 4/3 E* sqrt(R*) delta^(3/2),           S_n = 2 E* sqrt(R* delta)
//   F_n^d = -2 sqrt(5/6) beta sqrt(S_n m*) v_n
// Tangential (Mindlin 1949, no-slip):
//   S_t = 8 G* sqrt(R* delta),   F_t = -S_t xi - 2 sqrt(5/6) beta sqrt(S_t m*) v_t,  |F_t| <= mu
//   F_n with xi the tangential spring displacement (contact history).
// Effective values: 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2, 1/G* = (2-nu1)/G1 + (2-nu2)/G2,
// 1/R* = 1/R1 + 1/R2, 1/m* = 1/m1 + 1/m2 (a wall has R, m = infinity).
//
// Damping law, chosen per material pair (Interaction::damping). With this damping form the
// coefficient of restitution does not depend on the impact speed, only on beta:
//   standard (default): beta = -ln e / sqrt(ln^2 e + pi^2), the formula of EDEM's and LIGGGHTS'
//     Hertz-Mindlin. It is exact for a linear spring, not for Hertz's: a Hertz impact then
//     rebounds with RestitutionForBeta(beta) > e (0.897 for e = 0.88, 0.749 for e = 0.7).
//   exact_restitution: beta solved from the nondimensional Hertz impact
//     x'' = -x^(3/2) - zeta x^(1/4) x',  x(0) = 0, x'(0) = 1,  zeta = sqrt(5) beta
//     (total normal force clamped at >= 0: non-cohesive contact) so that the rebound speed
//     |x'(end)| equals e to 1e-9: a binary collision has exactly the material's e.
//
// Rolling friction, chosen per material pair (Interaction::rolling_model). F_n is the contact's
// normal force, R_i = r_i - delta/2 the distance from particle i's centre to the contact point
// (the middle of the overlap), w the angular velocities [rad/s]:
//   edem (default): EDEM's standard rolling friction (EDEM theory reference guide):
//       M_i = -mu_r F_n R_i w_i / |w_i|
//     each particle against its own spin, so the two torques of a pair are not equal and
//     opposite: a pair spinning together as one rigid body is braked by mu_r F_n (R_a + R_b).
//     For a clump, R_i and w_i are those of the sphere that touches (its body's spin).
//   cdt: LIGGGHTS' constant directional torque (LIGGGHTS-PUBLIC 3.8 rolling_model_cdt.h; Ai et
//     al. 2011, type A), its normal (twist) part removed after normalising:
//       M_a = -mu_r R* F_e (w_rel - (w_rel . n) n) / |w_rel|,  M_b = -M_a,  w_rel = w_a - w_b
//     with F_e = 4/3 E* sqrt(R*) delta^(3/2) the elastic normal force, as LIGGGHTS takes it. A
//     spin about n gets no torque.
//   legacy: scoopsim before issue 18, against the whole relative spin (twist too):
//       M_a = -mu_r R* F_n w_rel / |w_rel|,  M_b = -M_a
// Each torque's size is capped at |w| / (dt (1/I_a + 1/I_b)), with w the spin it acts against,
// so that it alone cannot reverse that spin within one step. A wall or mesh feels -M_a; whether
// that counts in the mesh's torque is SystemConfig::mesh_rolling_torque (EDEM: off by default).
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
  RollingModel rolling_model = RollingModel::kEdem;
};

PairConstants MakePairConstants(const Material& a, const Material& b, const Interaction& i);

// Coefficient of restitution of the nondimensional Hertz impact with damping parameter beta.
double RestitutionForBeta(double beta);
// Inverse of RestitutionForBeta on (0, 1]: the beta that gives restitution e (exact_restitution).
double BetaForRestitution(double e);
// The standard law's beta = -ln e / sqrt(ln^2 e + pi^2) (> 0 for e < 1, 0 for e = 1).
inline double StandardBeta(double e) {
  const double l = std::log(e);
  return -l / std::sqrt(l * l + M_PI * M_PI);
}
// The beta of a material pair under its damping law.
double DampingBeta(const Interaction& i);

// Closed form of the elastic Hertz normal force [N] (for tests and energy bookkeeping).
inline double HertzForce(double e_star, double r_star, double delta) {
  return 4.0 / 3.0 * e_star * std::sqrt(r_star) * delta * std::sqrt(delta);
}

// Result of one particle-wall contact, as felt by the particle.
struct ContactForce {
  double fn = 0;  // normal force magnitude (>= 0) [N]; force on the particle is -fn * n
  Vec3 ft;        // tangential force on the particle [N]
  Vec3 mr;        // rolling-friction torque on the particle [N m]; the wall feels -mr
};

// The rolling-friction torque on a particle from a contact (the header gives each model):
// w_spin the spin it acts against (edem: the particle's own; cdt, legacy: the relative spin
// w_a - w_b), r_lever the model's lever (edem: R_a = r_a - delta/2; else R*), force the model's
// normal force (cdt: elastic F_e; else F_n), inv_inertia_sum 1/I_a + 1/I_b.
inline Vec3 RollingTorque(RollingModel model, double mu_r, const Vec3& n, double r_lever,
                          double force, const Vec3& w_spin, double inv_inertia_sum, double dt) {
  const double w2 = Norm2(w_spin);
  if (mu_r <= 0.0 || w2 <= 0.0) return Vec3{};
  const double w = std::sqrt(w2);
  const double m = std::min(mu_r * r_lever * force, w / (dt * inv_inertia_sum));
  // cdt removes the torque's normal part: -m/|w| (w - (w . n) n).
  const Vec3 dir = model == RollingModel::kCdt ? w_spin - Dot(w_spin, n) * n : w_spin;
  return (-m / w) * dir;
}

// Evaluates the contact of a particle (radius r, mass m, angular velocity w_p) with a rigid wall
// (a plane or a mesh, angular velocity w_wall), R* = r and m* = m. n points from the particle to
// the wall (unit); delta > 0 is the overlap [m]; v_rel is the velocity of the wall's contact
// point minus the particle's [m/s]; inv_inertia is 1/I of the particle (the rolling torque is
// capped so that it cannot reverse the spin within one step); shear is the tangential history
// (updated in place).
inline ContactForce EvaluateWallContact(const PairConstants& c, const Vec3& n, double delta,
                                        double r, double m, const Vec3& v_rel, const Vec3& w_p,
                                        const Vec3& w_wall, double inv_inertia, double dt,
                                        Vec3& shear) {
  ContactForce out;
  const double vn = Dot(v_rel, n);
  const Vec3 vt = v_rel - vn * n;
  const double s = std::sqrt(r * delta);              // sqrt(R* delta) [m]
  const double sn = 2.0 * c.e_star * s;               // normal stiffness S_n [N/m]
  const double gamma_n = c.damp * std::sqrt(sn * m);  // [kg/s]
  const double fe = 2.0 / 3.0 * sn * delta;           // elastic (Hertz) force [N]
  const double fn = std::max(0.0, fe - gamma_n * vn);
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

  switch (c.rolling_model) {
    case RollingModel::kEdem:
      out.mr = RollingTorque(c.rolling_model, c.rolling_friction, n, r - 0.5 * delta, fn, w_p,
                             inv_inertia, dt);
      break;
    case RollingModel::kCdt:
      out.mr = RollingTorque(c.rolling_model, c.rolling_friction, n, r, fe, w_p - w_wall,
                             inv_inertia, dt);
      break;
    case RollingModel::kLegacy:
      out.mr = RollingTorque(c.rolling_model, c.rolling_friction, n, r, fn, w_p - w_wall,
                             inv_inertia, dt);
      break;
  }
  return out;
}

}  // namespace dem

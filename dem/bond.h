// Breakable bonds between spheres: the parallel bond of Potyondy & Cundall (2004), "A
// bonded-particle model for rock", Int. J. Rock Mech. Min. Sci. 41, 1329-1364 (section 2.2,
// eqs. 7-13 and 17-18), incremental as PFC3D's parallel bond model (Itasca) writes it. Public
// header of the dem module.
//
// A bond between spheres a and b is a disk of cement at the contact point, in parallel with the
// Hertz-Mindlin contact (dem/contact.h), which acts as before whenever the spheres overlap:
//   radius        R = lambda min(R_a, R_b)                         (lambda: radius_multiplier)
//   area, inertia A = pi R^2,  I = pi R^4 / 4,  J = pi R^4 / 2
//   stiffness     k_n = E_b / L (normal, per unit area) [Pa/m],  L = R_a + R_b
//                 k_s = k_n / stiffness_ratio (shear, per unit area)
// The contact point x_c lies on the line of centres at the middle of the gap (or overlap) g =
// d - R_a - R_b, as the contact law takes it: x_c - x_a = (R_a + g/2) n, x_c - x_b =
// -(R_b + g/2) n, with n the unit normal from a to b. Over a step of dt, with the velocities of
// the half step (velocity Verlet's, so that dU is the step's displacement), the relative motion of
// b against a at the contact point is
//   dU   = [(v_b + w_b x (x_c - x_b)) - (v_a + w_a x (x_c - x_a))] dt
//   dU_n = dU . n,  dU_s = dU - dU_n n           (normal, shear displacement increments)
//   dth  = (w_b - w_a) dt,  dth_n = dth . n,  dth_s = dth - dth_n n   (twist, bending)
// and the bond's force and moment grow as (PC2004 eqs. 9-11; F_n: tension positive)
//   dF_n = k_n A dU_n,  dF_s = -k_s A dU_s,  dM_t = -k_s J dth_n,  dM_b = -k_n I dth_s
// Before the increments are added, the shear force F_s and the bending moment M_b, vectors in the
// contact plane, are carried with it: rotated by the smallest rotation that takes the last step's
// normal to this one (Rodrigues), then about n by the pair's mean spin (w_a + w_b)/2 . n dt (a
// Cayley rotation, exact in length), as PFC3D does, so that a bonded pair turning as one rigid
// body keeps its bond's state. The force and moment on b are
//   F = -F_n n + F_s,   M = M_t n + M_b,   torque on b: M + (x_c - x_b) x F
// and a feels -F, -M and torque -M + (x_c - x_a) x (-F); the total angular momentum is kept. The
// largest stresses at the disk's rim (PC2004 eq. 12):
//   sigma = F_n / A + |M_b| R / I        (tension positive)
//   tau   = |F_s| / A + |M_t| R / J
// The bond breaks for good (PC2004 section 2.2; Mohr-Coulomb shear strength of PFC3D's
// pb_coh, pb_fa): in tension when sigma >= tensile_strength, else in shear when
// tau >= cohesion - (F_n / A) tan(friction_angle) (compression, F_n < 0, raises it). A bond that
// breaks in a step applies nothing in that step. Optional viscous damping (not in the reference:
// the bonded pair rings undamped there): damping_ratio of critical on each of the four springs,
// with the pair's reduced mass m* = m_a m_b / (m_a + m_b) and reduced moment of inertia
// I* = I_a I_b / (I_a + I_b) (I = 2/5 m r^2):
//   F_d = -2 z sqrt(k_n A m*) (v_rel . n) n - 2 z sqrt(k_s A m*) v_rel,s      (v_rel = dU / dt)
//   M_d = -2 z sqrt(k_s J I*) (w_rel . n) n - 2 z sqrt(k_n I I*) w_rel,s
// added to F and M on b (and taken from a) but not to the stored state, and not counted in the
// stresses. Elastic energy of a bond: F_n^2 / (2 k_n A) + |F_s|^2 / (2 k_s A) + M_t^2 / (2 k_s J)
// + |M_b|^2 / (2 k_n I).
#pragma once

#include <cstdint>
#include <vector>

#include "dem/vec3.h"

namespace dem {

// The bond law's parameters as a scene gives them (strengths before any grading with depth).
struct BondParams {
  double radius_multiplier = 1.0;  // lambda [-]
  double modulus = 0;              // E_b [Pa]
  double stiffness_ratio = 1.0;    // k_n / k_s [-]
  double tensile_strength = 0;     // sigma_c [Pa]
  double cohesion = 0;             // c [Pa]
  double friction_angle = 0;       // phi [rad]
  double damping_ratio = 0;        // of critical, on each spring [-]
};

// One bond, intact or broken. Its state (force, moment) is in world axes.
struct Bond {
  int64_t a = 0, b = 0;         // persistent ids of the two spheres, a < b (AddBonds checks)
  double radius = 0;            // R [m]
  double kn = 0, ks = 0;        // per unit area [Pa/m]
  double tensile_strength = 0;  // [Pa]
  double cohesion = 0;          // [Pa]
  double tan_friction = 0;      // tan(phi) [-]
  double damping_ratio = 0;     // [-]
  double fn = 0;                // normal force, tension positive [N]
  Vec3 fs;                      // shear force on b [N]
  double mt = 0;                // twisting moment on b about n [N m]
  Vec3 mb;                      // bending moment on b [N m]
  Vec3 normal;                  // n at the last step, a to b [-]; zero: AddBonds takes it
                                // from the positions
  bool intact = true;
};

enum class BondBreakMode : uint8_t { kTension = 1, kShear = 2 };

// A bond that broke in a step.
struct BondBreak {
  double time = 0;  // end of the step it broke in [s]
  int64_t a = 0, b = 0;
  Vec3 position;  // the contact point then [m]
  BondBreakMode mode = BondBreakMode::kTension;
  double stress = 0;  // the stress that broke it (sigma or tau) [Pa]
};

// The bond between spheres (ida, ra) and (idb, rb) at centre distance `distance` [m], unloaded
// (the ids are put in order a < b); its two strengths (tensile_strength, cohesion) are the
// params' times strength_scale (grading with depth); the friction angle is not scaled. L = R_a +
// R_b as PFC3D takes it: `distance` only has to be > 0. Throws std::invalid_argument on a bad
// value (radii, distance, modulus, stiffness ratio, strengths or multiplier <= 0 or NaN, friction
// angle outside [0, pi/2), damping ratio < 0).
Bond MakeBond(int64_t ida, double ra, int64_t idb, double rb, double distance,
              const BondParams& params, double strength_scale = 1.0);

// The largest step at which velocity Verlet integrates bonded spheres stably: for two equal
// spheres of `radius` and `density` bonded with `params` at distance 2 r, 2 / omega_max over the
// bond's translational and rotational modes (the shear spring's moment arm included, and the
// damping's share), divided by sqrt(12) for a sphere's many bonds (a bound for up to 12 bonds a
// sphere; an fcc lattice goes unstable from 1.5x it). The derivation and measurements are written
// at the definition; a test steps a bonded lattice at it (energy kept) and at 3x it (unstable).
// The smallest spheres give the smallest step. [s]
double BondCriticalStep(double radius, double density, const BondParams& params);

// The bond's elastic energy (above) [J].
double BondEnergy(const Bond& bond);
// Its largest normal and shear stresses at the rim, sigma and tau (above) [Pa].
double BondSigma(const Bond& bond);
double BondTau(const Bond& bond);

}  // namespace dem

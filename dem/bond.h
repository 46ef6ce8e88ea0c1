// Breakable bonds between spheres: the parallel bond of Potyondy & Cundall (2004), "A
// bonded-particle model for rock", Int. J. Rock Mech. Min. Sci. 41, 1329-1364 (section 2.2), as
// PFC3D's linear parallel bond model (Itasca) writes it. Public header of the dem module.
//
// A bond between spheres a and b is a disk of cement at the contact point, in parallel with the
// Hertz-Mindlin contact (dem/contact.h), which acts as before whenever the spheres overlap:
//   radius        R = lambda min(R_a, R_b)                         (lambda: radius_multiplier)
//   area, inertia A = pi R^2,  I = pi R^4 / 4,  J = pi R^4 / 2
//   stiffness     k_n = E_b / L (normal, per unit area) [Pa/m],  L = R_a + R_b at creation
//                 k_s = k_n / stiffness_ratio (shear, per unit area)
// With n the unit normal from a to b and the relative motion of b against a at the contact point
// over a step (dU_n, dU_s: normal and shear displacement increments; dth_n, dth_s: twist and
// bending rotation increments of b against a), the bond's force and moment on b grow as
//   dF_n = -k_n A dU_n  (tension when the spheres part: F_n > 0 is tension)
//   dF_s = -k_s A dU_s,   dM_t = -k_s J dth_n,   dM_b = -k_n I dth_s
// and the shear force and bending moment are carried with the contact plane (rotated with n) as
// the contact's tangential spring is. Sphere a feels the opposite force and moment, plus the
// moment of the force about its centre. The largest stresses at the disk's rim:
//   sigma = F_n / A + |M_b| R / I        (tension positive)
//   tau   = |F_s| / A + |M_t| R / J
// The bond breaks for good, in tension when sigma >= tensile_strength, else in shear when
// tau >= cohesion - (F_n / A) tan(friction_angle) (a Mohr-Coulomb strength: compression, F_n < 0,
// raises it). Optional viscous damping: damping_ratio of critical on each of the four springs
// (with the pair's reduced mass and reduced moment of inertia), 0 for the undamped bond of the
// reference.
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
  int64_t a = 0, b = 0;             // persistent ids of the two spheres, a < b
  double radius = 0;                // R [m]
  double kn = 0, ks = 0;            // per unit area [Pa/m]
  double tensile_strength = 0;      // [Pa]
  double cohesion = 0;              // [Pa]
  double tan_friction = 0;          // tan(phi) [-]
  double damping_ratio = 0;         // [-]
  double fn = 0;                    // normal force, tension positive [N]
  Vec3 fs;                          // shear force on b [N]
  double mt = 0;                    // twisting moment on b about n [N m]
  Vec3 mb;                          // bending moment on b [N m]
  Vec3 normal;                      // n at the last step, a to b [-]
  bool intact = true;
};

enum class BondBreakMode : uint8_t { kTension = 1, kShear = 2 };

// A bond that broke in a step.
struct BondBreak {
  double time = 0;    // end of the step it broke in [s]
  int64_t a = 0, b = 0;
  Vec3 position;      // the contact point then [m]
  BondBreakMode mode = BondBreakMode::kTension;
  double stress = 0;  // the stress that broke it (sigma or tau) [Pa]
};

// The bond between spheres (ida, ra) and (idb, rb) at centre distance `distance` [m]; its three
// strengths are the params' times strength_scale (grading with depth).
Bond MakeBond(int64_t ida, double ra, int64_t idb, double rb, double distance,
              const BondParams& params, double strength_scale = 1.0);

// The largest step at which velocity Verlet integrates bonded spheres stably, with a margin:
// for two equal spheres of `radius` and `density` bonded with `params` at distance 2 r, the
// smallest of sqrt(mass / stiffness) over the bond's translational and rotational modes (the
// shear spring's moment arm included), times a safety factor for a sphere's many bonds. The
// formula and its factor are written at the definition and a test steps a bonded lattice at it
// (energy conserved) and at a few times it (unstable). The smallest spheres give the smallest
// step. [s]
double BondCriticalStep(double radius, double density, const BondParams& params);

}  // namespace dem

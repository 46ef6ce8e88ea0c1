// Calibration of the parallel bond (dem/bond.h) against laboratory strengths: the bond's
// parameters in, the bonded material's unconfined compressive strength (UCS), Brazilian tensile
// strength and Young's modulus out, as Potyondy & Cundall (2004), "A bonded-particle model for
// rock", Int. J. Rock Mech. Min. Sci. 41, 1329-1364, section 3, calibrate theirs. `scoopsim
// calibrate bonds` (tools/main.cpp) runs it.
//
// Samples (MakeBondSample): spheres of radii uniform in r (1 -/+ spread) are put on a jittered
// lattice (dem::InsertSpheres) in a box of planes and settled under 4 g with frictionless,
// strongly damped contacts (G at most 1e7 Pa: only the geometry is kept), then a lid comes down
// onto them to the sample's height (or until it bears the weight's pressure), so that the top is
// as flat as the floor (a dense random packing, solid fraction ~0.6); the spheres are then cut
// to the shape:
//   compression  a square prism W x W x H, H = 2 W (the box itself, lidded: all its spheres);
//   Brazilian    a disk of diameter D and thickness t = D / 2 (ISRM's t/D ~ 0.5), its axis along
//                y, horizontal: a D x t slab lidded at D cos(15 deg) and cut to the circle, so
//                that it has two flats of 2 alpha = 30 deg where the platens bear (a flattened
//                Brazilian disc; a round disk of coarse spheres touches a platen on one sphere).
// W and D are chosen so that each sample holds about `particles` spheres.
//
// A test (RunPlatenTest): the sample without gravity relaxes unbonded by kinetic damping until no
// contact pushes (at most 5000 steps) and is stopped; every pair of spheres whose surfaces are
// closer than `gap` is bonded (System::PairsWithinGap, dem::MakeBond with the row's strength
// scale), spheres left with fewer than 3 bonds removed first (Potyondy & Cundall's "floaters"). It
// is loaded through gripped ends: the spheres whose centres lie within one mean diameter of its
// lowest and highest points are the grips, driven vertically at +-v/2 each (their vertical velocity
// is set every step so that velocity Verlet moves them exactly so; the prism's are free sideways
// and in rotation, as on frictionless platens but unable to part from them; the disk's are held
// sideways, as by jaws with friction), so that the load enters through all the end spheres' bonds
// at once. Loaded through platens instead (rigid meshes bearing on the ends' spheres through Hertz
// contacts), a few end contacts carried the whole load and set the peak: the strengths were not
// proportional to the bond strengths (UCS x2.9 and sigma_t x11 for a doubling) and depended on the
// speed (+46% at half of it). The load P is the mean of the forces the two grips bear from the rest
// of the sample (their own bonds and contacts cancel in each grip's sum), averaged over blocks of
// one wave transit of the sample; the platen strain is the grips' travel over the sample's height
// at the start, eps = v t / h0. The test stops once P has fallen below `stop_fraction` of its peak
// with bonds broken and the grips half as far again as at the peak (failure), or at `max_strain`
// (the limit: unbreakable bonds end there).
//   UCS        = P_peak / W^2                              (the prism's cross-section)
//   sigma_t    = 2 P_peak / (pi D t)                       (ISRM 1978 suggested method, Brazilian;
//                the disk's two flats are its grips)
//   E_sample   = least-squares slope of sigma = P / W^2 against the gauge strain over the blocks
//                before the peak with sigma in [0.1, 0.5] UCS (the prism only). The gauge
//                strain is that between the mean heights of the spheres starting in the bands at
//                20-30% and 70-80% of the height, as a lab's gauges on the middle of a sample.
// Quasi-static loading: the speed is v = speed_factor x eps_ref c / kTransits with
// c = sqrt(E_b / rho) the bond material's wave speed and eps_ref = min(sigma_c / E_b, max_strain)
// the strain at which a lone bond would break in tension: the grips close by eps_ref in
// kTransits = 100 wave transits of the sample's height. The loading's time scale thus follows the
// strength (each row about the same number of steps to its peak); halving the speed
// (--rate-check) shows how far the peak still depends on it.
//
// What a user does with it: pick the material, the sphere size and the bond's modulus and
// strength ratios, run one or a few strength scales, and scale the bond strengths by the ratio
// of the literature's UCS (or tensile strength) to the measured one. BPM theory makes UCS and
// sigma_t proportional to the bond strengths at fixed stiffness and geometry (Potyondy & Cundall
// 2004, section 3.1), which these samples show (tests/sim/calibrate_test.cpp: x2.00 for x2;
// bench/results/vm/bond_calibration.csv); their ratio UCS / sigma_t (direct) is set by the
// bond's cohesion over its tensile strength (1.75, 3.1, 4.4 for c / sigma_c = 1, 2, 4 with
// k_n/k_s = 1, phi = 0), the geometry and the stiffness ratio, not by the scale. The Brazilian
// disk at c = sigma_c fails in shear under its gripped flats and reads well below the direct
// tension (docs/bonds.md, "Calibration").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dem/bond.h"
#include "dem/material.h"
#include "dem/vec3.h"

namespace sim {

enum class BondSampleShape { kPrism, kDisk };

// A settled sample, cut to its shape; its spheres in a fixed order.
struct BondSample {
  BondSampleShape shape = BondSampleShape::kPrism;
  dem::Material material;      // the particles' material (density, G, nu)
  std::vector<dem::Vec3> x;    // centres [m] (N)
  std::vector<double> radius;  // [m] (N)
  double width = 0;            // prism: W, the side of its square cross-section [m]
  double height = 0;           // prism: H, nominal (2 W) [m]
  double diameter = 0;         // disk: D [m]
  double thickness = 0;        // disk: t [m]
  double solid_fraction = 0;   // of the spheres kept, over the nominal shape's volume [-]
  int64_t settle_steps = 0;    // steps of the settling
};

// How a sample is made.
struct BondSampleSpec {
  dem::Material material;
  dem::Interaction interaction;  // particle-particle, from the materials file
  double radius = 2.5e-3;        // mean sphere radius r [m]
  double spread = 0.2;           // radii uniform in r [1 - spread, 1 + spread], in [0, 0.5]
  int64_t particles = 1500;      // spheres in the sample, about
  uint64_t seed = 1;
  int threads = 1;
};
// Throws std::runtime_error when the settling goes unstable.
BondSample MakeBondSample(const BondSampleSpec& spec, BondSampleShape shape);

// How a test is run.
struct PlatenTestSpec {
  dem::Interaction interaction;    // particle-particle, from the materials file
  dem::BondParams bond;            // strengths at scale 1
  double gap = 0;                  // bond spheres whose surfaces are closer than this [m]
  double strength_scale = 1;       // the row's scale of the three strengths
  double rayleigh_fraction = 0.2;  // dt = min(fraction t_R, BondCriticalStep) [-]
  double speed_factor = 1;         // v = speed_factor x the quasi-static speed above [-]
  double max_strain = 0.05;        // the grips' strain limit [-]
  double stop_fraction = 0.5;      // stop once P < this x peak after bonds broke [-]
  // Pull the grips apart rather than push them together: the prism's direct tension test,
  // sigma_t = P_peak / W^2 (strength then holds it, and E_sample is the modulus in tension).
  bool pull = false;
  int threads = 1;
};

// What a test measured.
struct PlatenTestResult {
  double peak_force = 0;       // P_peak [N]
  double strength = 0;         // UCS or sigma_t [Pa]
  double young_modulus = 0;    // E_sample [Pa] (compression; 0 for the disk or too few points)
  double strain_at_peak = 0;   // [-]
  double platen_speed = 0;     // v [m/s]
  double time_step = 0;        // [s]
  int64_t particles = 0;       // in the test
  int64_t removed = 0;         // spheres of the sample with too few bonds, left out
  int64_t bonds = 0;           // made
  int64_t gripped = 0;         // spheres in the two grips
  int64_t broken_at_peak = 0;  // bonds broken up to the peak's step
  int64_t broken = 0;          // bonds broken by the end
  int64_t broken_tension = 0;  // of which in tension (the rest in shear)
  int64_t steps = 0;
  double max_overlap = 0;      // deepest overlap seen / the smaller diameter [-]
  bool reached_limit = false;  // stopped at max_strain rather than past the peak
  double cpu_s = 0;            // process CPU time of the test [s]
};
// Throws std::runtime_error when a step reports non-finite state, a runaway speed or a particle
// that left the domain.
PlatenTestResult RunPlatenTest(const BondSample& sample, const PlatenTestSpec& spec);

// `scoopsim calibrate bonds`: both samples made once, then per strength scale a compression and
// a Brazilian test; a CSV table and a line per row on stdout.
struct BondCalibrationOptions {
  std::string materials_path;  // "" = the source tree's scenes/materials.yaml
  std::string material = "ice";
  double shear_modulus = 0;   // G of the particles [Pa]; 0 = the material's
  BondSampleSpec sample;      // material and interaction filled from the file
  dem::BondParams bond;       // modulus 0 = the particles' Young's modulus
  double gap_fraction = 0.1;  // gap = this x the mean radius [-]
  std::vector<double> scales{1.0};
  PlatenTestSpec test;      // bond, gap and scale filled per row
  bool rate_check = false;  // rerun the first scale at half the speed
  std::string output = "out/bond_calibration.csv";
  bool quiet = false;
};
int RunBondCalibration(const BondCalibrationOptions& options);

// The command line that reproduces `options` (every option written out), for the CSV's header.
std::string BondCalibrationCommandLine(const BondCalibrationOptions& options);

}  // namespace sim

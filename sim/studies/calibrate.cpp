// Bond calibration: dense samples, tests through gripped ends, the table (sim/studies/calibrate.h).
#include "sim/studies/calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dem/insertion.h"
#include "dem/mesh.h"
#include "dem/system.h"
#include "sim/input/exit_status.h"
#include "sim/input/input_error.h"
#include "sim/input/scene.h"
#include "sim/studies/commands.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;
// Expected solid fraction of the settled packing (frictionless spheres under gravity, walls
// included), used only to size the box and the samples [-].
constexpr double kSettledFraction = 0.6;
// Spheres put in the box: this fraction of its volume, a little more than settles in it, so that
// the lid bears on them [-].
constexpr double kFillFraction = 0.62;
// The disk's two flats, where it is gripped, each subtend this angle at the centre (2 alpha;
// ISRM's curved jaws touch the disk over ~10 deg, a flattened disc over 20-30 deg; at D ~ 8-16
// sphere diameters a flat of 30 deg is 2-4 spheres wide) [rad].
constexpr double kFlatAngle = 30 * kPi / 180;
// Steps the unbonded sample relaxes before it is bonded, at most (RunPlatenTest).
constexpr int kRelaxSteps = 5000;
// A sphere of a sample with fewer bonds than this is removed before the test [-].
constexpr int kMinBonds = 3;
// Wave transits of the sample's height over which the grips close by the reference strain
// (calibrate.h: the quasi-static speed).
constexpr double kTransits = 100;
// The settling: gravity four times Earth's (the spheres' weight still overlaps them by under
// 1e-3 of a radius at G = 1e7 Pa), done when every sphere is slower than kQuiet sqrt(2 g r).
constexpr double kSettleGravity = 4 * 9.81;  // [m/s^2]
constexpr double kQuiet = 0.02;              // [-]
constexpr double kPrepShearModulus = 1e7;    // [Pa]

double CpuNow() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// ---------------------------------------------------------------------------------------------
// The sample: spheres on a jittered lattice in a box of planes, settled under gravity with
// frictionless, strongly damped contacts (restitution 0.2), which pack them to about random close
// packing; then a lid (a mesh) comes down onto them until it is at the sample's height or bears
// the weight's pressure at the floor, so that the sample's top is as flat as its floor (a rough
// end seats on a few spheres first, which softened the measured modulus ~50x and halved the
// strength); then the spheres are cut to the shape.

// A square of half side `half` in its body frame's z = 0 plane, its triangles counter-clockwise
// seen from +z (`up`) or -z: the lid.
dem::TriangleMesh Square(const std::string& name, double half, bool up, int material) {
  dem::TriangleMesh mesh;
  mesh.name = name;
  mesh.vertices = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
  if (up) {
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  } else {
    mesh.triangles = {{0, 2, 1}, {0, 3, 2}};
  }
  mesh.material = material;
  return mesh;
}

// Steps `system` (its mesh 0 the lid, at `lid_z` and moving at `lid_v`) until every sphere is
// slower than `quiet`, checked every 100 steps, once `min_time` has passed; at most `max_time`.
// With `lid`, the lid comes down at `lid_v` until it reaches `lid_target` or the spheres push on
// it with `lid_force`, and stays there. Returns the steps.
struct Lid {
  bool on = false;
  double z = 0, speed = 0, target = 0, force = 0;
  double cx = 0, cy = 0;
};
int64_t StepUntilQuiet(dem::System* system, double quiet, double min_time, double max_time,
                       Lid* lid) {
  const double dt = system->config().time_step;
  const double t0 = system->time();
  const int64_t max_steps = static_cast<int64_t>(std::ceil(max_time / dt));
  bool lid_moving = lid->on;
  double lid_push = 0;  // sum of the lid's force over the steps since the last check [N]
  int64_t steps = 0;
  for (; steps < max_steps; ++steps) {
    if (lid->on) {
      if (lid_moving && lid->z - lid->speed * dt <= lid->target) lid_moving = false;
      if (lid_moving) lid->z -= lid->speed * dt;
      dem::MeshMotion motion;
      motion.pose.position = {lid->cx, lid->cy, lid->z};
      motion.velocity = {0, 0, lid_moving ? -lid->speed : 0.0};
      system->SetMeshMotion(0, motion);
    }
    const dem::StepStatus status = system->Step();
    if ((status.flags & ~static_cast<uint32_t>(dem::kExcessiveOverlap)) != 0)
      throw std::runtime_error("calibrate bonds: the sample's settling went unstable: " +
                               status.message);
    if (lid->on) lid_push += system->mesh_wrench(0).force.z;
    if (steps % 100 != 99) continue;
    // The lid's push, averaged over the 100 steps (its first touch is an impact).
    if (lid_moving && lid_push / 100 >= lid->force) lid_moving = false;
    lid_push = 0;
    if (system->time() - t0 < min_time || lid_moving) continue;
    double vmax = 0;
    for (const dem::Vec3& v : system->particles().v) vmax = std::max(vmax, dem::Norm(v));
    if (vmax < quiet) break;
  }
  return steps + 1;
}

BondSample SettleAndCut(const BondSampleSpec& spec, BondSampleShape shape) {
  const double r = spec.radius, s = spec.spread;
  const double r_min = r * (1 - s), r_max = r * (1 + s);
  // Mean sphere volume for radii uniform in r [1 - s, 1 + s]: E[r^3] = r^3 (1 + s^2).
  const double v_mean = 4.0 / 3.0 * kPi * r * r * r * (1 + s * s);
  const double n = static_cast<double>(spec.particles);
  BondSample sample;
  sample.shape = shape;
  sample.material = spec.material;
  // Box floor [0, wx] x [0, wy], filled to `height` under the lid: the prism itself, or a slab
  // whose floor and lid are the disk's two flats (2 alpha = kFlatAngle).
  double wx = 0, wy = 0, height = 0;
  if (shape == BondSampleShape::kPrism) {
    const double w = std::cbrt(n * v_mean / (2 * kSettledFraction));  // W^2 2W phi = N v
    sample.width = w;
    wx = wy = w;
    height = 2 * w;
  } else {
    const double d = std::cbrt(8 * n * v_mean / (kPi * kSettledFraction));  // pi D^2/4 D/2 phi
    sample.diameter = d;
    sample.thickness = d / 2;
    wx = d + 4 * r_max;  // the circle clear of the side walls' ordered layer
    wy = d / 2;
    height = d * std::cos(0.5 * kFlatAngle);
  }
  // A little more than fills it at the expected fraction, so that the lid bears on the spheres.
  const int64_t fill_count =
      static_cast<int64_t>(std::ceil(wx * wy * height * kFillFraction / v_mean));
  // InsertSpheres packs at most ~0.5, less in a narrow box (whole lattice sites only): a box
  // tall enough at 0.45, made taller until every sphere fits.
  double box_height = fill_count * v_mean / (wx * wy * 0.45) + 2 * r_max;
  std::vector<dem::SphereSeed> seeds;
  for (;;) {
    dem::Rng rng(spec.seed);
    seeds = dem::InsertSpheres({0, 0, 0}, {wx, wy, box_height}, fill_count, r_min, r_max, 0.5, rng);
    if (static_cast<int64_t>(seeds.size()) >= fill_count) break;
    box_height *= 1.25;
  }

  // The packing is made with G at most kPrepShearModulus: its geometry is all that is kept, and
  // the settling's steps grow as sqrt(G) (its time is gravity's).
  dem::Material prep_material = spec.material;
  prep_material.shear_modulus = std::min(prep_material.shear_modulus, kPrepShearModulus);
  dem::MaterialTable table;
  const int m = table.Add(prep_material);
  dem::Interaction settle = spec.interaction;
  settle.restitution = 0.2;
  settle.friction = 0;
  settle.rolling_friction = 0;
  table.SetInteraction(m, m, settle);
  dem::SystemConfig config;
  config.gravity = {0, 0, -kSettleGravity};
  config.time_step = 0.2 * dem::RayleighTimeStep(r_min, prep_material);
  config.skin = 0.5 * r;
  const double margin = 4 * r_max;
  config.domain_min = {-margin, -margin, -margin};
  config.domain_max = {wx + margin, wy + margin, box_height + margin};
  config.planes = {{"floor", {0, 0, 0}, {0, 0, 1}, m},
                   {"x0", {0, 0, 0}, {1, 0, 0}, m},
                   {"x1", {wx, 0, 0}, {-1, 0, 0}, m},
                   {"y0", {0, 0, 0}, {0, 1, 0}, m},
                   {"y1", {0, wy, 0}, {0, -1, 0}, m}};
  dem::System system(table, config);
  system.set_num_threads(spec.threads);
  system.Reserve(seeds.size());
  for (const dem::SphereSeed& seed : seeds) system.AddParticle(seed.x, {}, {}, seed.radius, m);
  const int lid_mesh = system.AddMesh(Square("lid", std::max(wx, wy), false, m));
  (void)lid_mesh;  // mesh 0, as StepUntilQuiet takes it

  // Settled: every sphere slower than kQuiet sqrt(2 g r), after at least the time to fall the
  // box's height; at most 2 s. The lid waits above the box.
  const double quiet = kQuiet * std::sqrt(2 * kSettleGravity * r);
  Lid lid;
  lid.cx = 0.5 * wx;
  lid.cy = 0.5 * wy;
  lid.z = box_height + margin / 2;
  dem::MeshMotion parked;
  parked.pose.position = {lid.cx, lid.cy, lid.z};
  system.SetMeshMotion(0, parked);
  sample.settle_steps =
      StepUntilQuiet(&system, quiet, std::sqrt(2 * box_height / kSettleGravity), 2.0, &lid);
  // The lid: from just above the highest sphere down at 0.02 sqrt(2 g r) to the sample's height,
  // or until it bears the weight's pressure at the floor (rho phi g height); then quiet again.
  double top = 0;
  for (size_t i = 0; i < system.particles().size(); ++i)
    top = std::max(top, system.particles().x[i].z + system.particles().radius[i]);
  lid.on = true;
  lid.z = std::max(top, height) + 0.1 * r;
  lid.speed = 0.02 * std::sqrt(2 * kSettleGravity * r);
  lid.target = height;
  lid.force = spec.material.density * kSettledFraction * kSettleGravity * height * wx * wy;
  sample.settle_steps += StepUntilQuiet(&system, quiet, 0, 1.0, &lid);
  const double lid_z = lid.z;

  // Cut: spheres in persistent-id order (the order inserted), kept when wholly inside.
  sample.height = lid_z;
  const dem::Particles& p = system.particles();
  std::vector<size_t> order(p.size());
  for (size_t i = 0; i < p.size(); ++i) order[static_cast<size_t>(p.id[i])] = i;
  double solid = 0;
  for (const size_t i : order) {
    const dem::Vec3& x = p.x[i];
    const double ri = p.radius[i];
    bool keep = true;
    if (shape == BondSampleShape::kDisk) {
      const double half = sample.diameter / 2;
      keep = std::hypot(x.x - 0.5 * wx, x.z - 0.5 * lid_z) + ri <= half;
    }
    if (!keep) continue;
    sample.x.push_back(x);
    sample.radius.push_back(ri);
    solid += 4.0 / 3.0 * kPi * ri * ri * ri;
  }
  const double volume = shape == BondSampleShape::kPrism
                            ? sample.width * sample.width * sample.height
                            : kPi / 4 * sample.diameter * sample.diameter * sample.thickness;
  sample.solid_fraction = solid / volume;
  return sample;
}

// Least-squares slope of y against x.
double Slope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  if (n < 3) return 0;
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0;
}

}  // namespace

BondSample MakeBondSample(const BondSampleSpec& spec, BondSampleShape shape) {
  return SettleAndCut(spec, shape);
}

PlatenTestResult RunPlatenTest(const BondSample& sample, const PlatenTestSpec& spec) {
  const double cpu0 = CpuNow();
  PlatenTestResult out;
  const size_t n = sample.x.size();
  if (n == 0) throw std::runtime_error("calibrate bonds: an empty sample");

  // The particles; the ends are gripped (below), so there is no platen to touch.
  dem::MaterialTable table;
  const int m = table.Add(sample.material);
  table.SetInteraction(m, m, spec.interaction);

  dem::Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  double r_min = 1e300, r_sum = 0;
  for (size_t i = 0; i < n; ++i) {
    const double r = sample.radius[i];
    const dem::Vec3& x = sample.x[i];
    lo = {std::min(lo.x, x.x - r), std::min(lo.y, x.y - r), std::min(lo.z, x.z - r)};
    hi = {std::max(hi.x, x.x + r), std::max(hi.y, x.y + r), std::max(hi.z, x.z + r)};
    r_min = std::min(r_min, r);
    r_sum += r;
  }
  const double r_mean = r_sum / n;
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});

  // The step: the contact's Rayleigh step or the bond's critical step, the smaller.
  const double dt = std::min(spec.rayleigh_fraction * dem::RayleighTimeStep(r_min, sample.material),
                             dem::BondCriticalStep(r_min, sample.material.density, spec.bond));
  out.time_step = dt;
  dem::SystemConfig config;
  config.gravity = {0, 0, 0};
  config.time_step = dt;
  config.skin = 0.5 * r_mean;
  config.domain_min = lo - dem::Vec3{2 * extent, 2 * extent, 2 * extent};
  config.domain_max = hi + dem::Vec3{2 * extent, 2 * extent, 2 * extent};
  dem::System system(table, config);
  system.set_num_threads(spec.threads);
  system.Reserve(n);
  std::vector<int64_t> ids(n);
  for (size_t i = 0; i < n; ++i)
    ids[i] = system.AddParticle(sample.x[i], {}, {}, sample.radius[i], m);

  // The sample relaxes without gravity and walls before it is bonded: the contacts' overlaps
  // from the settling (the weight and the lid's push, made at kPrepShearModulus) spring apart by
  // kinetic damping (every velocity zeroed whenever the kinetic energy falls: the energy is taken
  // out at its peaks, the standard dynamic relaxation), until a step ends with no sphere moving
  // (no contact pushes any more) or after kRelaxSteps, so that the bonds start with the packing
  // as it settled and no locked-in stress. Let go freely, the spheres flew apart (a 310-sphere
  // sample of r 5 mm at G 1e8 Pa kept 203 of its 928 pairs within the gap); zeroed at every step
  // (an overdamped descent), the collective modes took thousands of steps and 20 kPa bonds broke
  // under the contacts' leftover push (UCS 0.012 MPa after 500 steps, 0.035 after 3,000; with
  // kinetic damping 0.028 after 500 and 3,000 alike, and x10.6 at 10x the strengths).
  dem::Particles& moving = system.mutable_particles();
  double last_energy = 0;
  for (int k = 0; k < kRelaxSteps; ++k) {
    const dem::StepStatus status = system.Step();
    if ((status.flags & ~static_cast<uint32_t>(dem::kExcessiveOverlap)) != 0)
      throw std::runtime_error("calibrate bonds: the sample's release went unstable: " +
                               status.message);
    double energy = 0;  // twice the translational kinetic energy [J]
    for (size_t i = 0; i < moving.size(); ++i) energy += moving.mass[i] * dem::Norm2(moving.v[i]);
    if (energy == 0.0) break;
    if (energy < last_energy) {
      std::fill(moving.v.begin(), moving.v.end(), dem::Vec3{});
      std::fill(moving.w.begin(), moving.w.end(), dem::Vec3{});
      energy = 0;
    }
    last_energy = energy;
  }
  std::fill(moving.v.begin(), moving.v.end(), dem::Vec3{});
  std::fill(moving.w.begin(), moving.w.end(), dem::Vec3{});
  system.Touch();
  system.set_time(0);

  // Bonds between the spheres closer than the gap, as a bed's are made. A sphere with fewer than
  // kMinBonds bonds is not held in the sample (a loose sphere at an end slides out sideways
  // and carries nothing): it is removed, and so on until every sphere has kMinBonds (Potyondy &
  // Cundall 2004, section 2.3, step 4, remove their "floaters" the same way).
  std::vector<size_t> index_of(n);
  for (size_t i = 0; i < n; ++i) index_of[static_cast<size_t>(ids[i])] = i;
  std::vector<std::pair<int64_t, int64_t>> pairs;
  for (;;) {
    pairs = system.PairsWithinGap(spec.gap);
    std::vector<int> count(n, 0);
    for (const auto& [a, b] : pairs) {
      ++count[index_of[static_cast<size_t>(a)]];
      ++count[index_of[static_cast<size_t>(b)]];
    }
    std::vector<int64_t> loose;
    for (const int64_t id : system.particles().id)
      if (count[index_of[static_cast<size_t>(id)]] < kMinBonds) loose.push_back(id);
    if (loose.empty()) break;
    out.removed += static_cast<int64_t>(loose.size());
    system.RemoveParticles(loose);
  }
  std::vector<dem::Bond> bonds;
  bonds.reserve(pairs.size());
  std::vector<size_t> slot(n);  // persistent id -> storage index now
  for (size_t k = 0; k < system.particles().size(); ++k)
    slot[static_cast<size_t>(system.particles().id[k])] = k;
  for (const auto& [a, b] : pairs) {
    const size_t i = index_of[static_cast<size_t>(a)], j = index_of[static_cast<size_t>(b)];
    const dem::Vec3 d = system.particles().x[slot[static_cast<size_t>(b)]] -
                        system.particles().x[slot[static_cast<size_t>(a)]];
    bonds.push_back(dem::MakeBond(a, sample.radius[i], b, sample.radius[j], dem::Norm(d), spec.bond,
                                  spec.strength_scale));
  }
  system.AddBonds(bonds);
  out.particles = static_cast<int64_t>(system.particles().size());
  out.bonds = static_cast<int64_t>(bonds.size());

  // The grips: the spheres whose centres lie within one mean diameter of the sample's lowest and
  // highest points (calibrate.h).
  double z_lo = 1e300, z_hi = -1e300;
  for (size_t i = 0; i < system.particles().size(); ++i) {
    z_lo = std::min(z_lo, system.particles().x[i].z - system.particles().radius[i]);
    z_hi = std::max(z_hi, system.particles().x[i].z + system.particles().radius[i]);
  }
  const double h0 = z_hi - z_lo;
  std::vector<int64_t> bottom_grip, top_grip;
  for (size_t i = 0; i < system.particles().size(); ++i) {
    const double z = system.particles().x[i].z;
    if (z - z_lo <= 2 * r_mean) bottom_grip.push_back(system.particles().id[i]);
    if (z_hi - z <= 2 * r_mean) top_grip.push_back(system.particles().id[i]);
  }
  out.gripped = static_cast<int64_t>(bottom_grip.size() + top_grip.size());

  // The quasi-static speed (calibrate.h): the grips close by eps_ref in kTransits transits.
  const double wave_speed = std::sqrt(spec.bond.modulus / sample.material.density);
  const double bond_strain = spec.bond.tensile_strength * spec.strength_scale / spec.bond.modulus;
  const double eps_ref =
      std::isfinite(bond_strain) ? std::min(bond_strain, spec.max_strain) : spec.max_strain;
  const double v = spec.speed_factor * eps_ref * wave_speed / kTransits;
  out.platen_speed = v;

  // The load is averaged over blocks of one wave transit (h0 / c) so that the peak is the
  // sample's, not a ringing's.
  const int64_t block = std::max<int64_t>(1, std::llround(h0 / wave_speed / dt));
  const double area = sample.shape == BondSampleShape::kPrism
                          ? sample.width * sample.width
                          : 0.5 * kPi * sample.diameter * sample.thickness;  // sigma_t = P / it
  std::vector<double> strain, stress;  // block means: grip strain, stress [-], [Pa]
  // The gauge (compression): the spheres whose centres start in the bands 20-30% and 70-80% of
  // the height; the strain between the bands' mean heights, as a lab's gauges on the sample's
  // middle measure it, without the ends' seating in series.
  std::vector<int64_t> low_band, high_band;
  double low0 = 0, high0 = 0;
  for (size_t i = 0; i < system.particles().size(); ++i) {
    const double f = (system.particles().x[i].z - z_lo) / h0;
    if (f >= 0.2 && f <= 0.3) low_band.push_back(system.particles().id[i]);
    if (f >= 0.7 && f <= 0.8) high_band.push_back(system.particles().id[i]);
  }
  // Each sphere's storage index by persistent id, made again after every step (a step may
  // reorder the storage); the gauge, the grips' drive and their forces read it.
  std::vector<size_t> at(static_cast<size_t>(ids.back()) + 1);
  auto index_ids = [&] {
    for (size_t i = 0; i < moving.size(); ++i) at[static_cast<size_t>(moving.id[i])] = i;
  };
  index_ids();
  auto band_height = [&](const std::vector<int64_t>& band) {
    double sum = 0;
    for (const int64_t id : band) sum += moving.x[at[static_cast<size_t>(id)]].z;
    return band.empty() ? 0.0 : sum / band.size();
  };
  low0 = band_height(low_band);
  high0 = band_height(high_band);
  const bool gauge = sample.shape == BondSampleShape::kPrism && !low_band.empty() &&
                     !high_band.empty() && high0 > low0;
  std::vector<double> gauge_strain;
  double load_sum = 0;
  int64_t in_block = 0, broken = 0, tension = 0, peak_block = -1;
  double peak = 0;
  const int64_t max_steps = static_cast<int64_t>(std::ceil(spec.max_strain * h0 / (v * dt))) + 1;
  const double sense = spec.pull ? -1.0 : 1.0;  // the grips close (+1) or part (-1)
  // Each step the grips' vertical velocity is set so that velocity Verlet's first half kick
  // (v += f dt / 2m, the force of the last step) brings it to +-v/2 before the drift: the grips
  // move as the platens would, and whatever they are pushed or pulled with is the load.
  auto grip_force = [&](const std::vector<int64_t>& grip) {
    double sum = 0;
    for (const int64_t id : grip) sum += moving.f[at[static_cast<size_t>(id)]].z;
    return sum;
  };
  // The prism's grips are free sideways (frictionless platens); the disk's are held sideways too,
  // as jaws with friction hold it: free, the narrow flats let the two halves slide past each
  // other, and the load fell with no bond broken.
  const bool held_sideways = sample.shape == BondSampleShape::kDisk;
  auto drive = [&](const std::vector<int64_t>& grip, double speed) {
    for (const int64_t id : grip) {
      const size_t i = at[static_cast<size_t>(id)];
      const double kick = 0.5 * dt * moving.inv_mass[i];
      moving.v[i].z = speed - kick * moving.f[i].z;
      if (held_sideways) {
        moving.v[i].x = -kick * moving.f[i].x;
        moving.v[i].y = -kick * moving.f[i].y;
      }
    }
  };
  for (int64_t step = 0; step < max_steps; ++step) {
    drive(bottom_grip, 0.5 * sense * v);
    drive(top_grip, -0.5 * sense * v);
    const dem::StepStatus status = system.Step();
    if ((status.flags & ~static_cast<uint32_t>(dem::kExcessiveOverlap)) != 0)
      throw std::runtime_error("calibrate bonds: the test went unstable: " + status.message);
    index_ids();
    out.steps = step + 1;
    out.max_overlap = std::max(out.max_overlap, system.neighbor_stats().max_overlap);
    for (const dem::BondBreak& b : system.TakeBondBreaks()) {
      ++broken;
      if (b.mode == dem::BondBreakMode::kTension) ++tension;
    }
    // The sample pushes the top grip up (+z) and the bottom one down in compression; the bonds
    // and contacts within a grip cancel in its sum.
    load_sum += 0.5 * sense * (grip_force(top_grip) - grip_force(bottom_grip));
    if (++in_block < block && step + 1 < max_steps) continue;
    const double load = load_sum / in_block;
    load_sum = 0;
    in_block = 0;
    strain.push_back(v * system.time() / h0);
    stress.push_back(load / area);
    if (gauge) {
      const double low = band_height(low_band), high = band_height(high_band);
      gauge_strain.push_back(sense * (1 - (high - low) / (high0 - low0)));
    }
    if (load > peak) {
      peak = load;
      peak_block = static_cast<int64_t>(stress.size()) - 1;
      out.broken_at_peak = broken;
    }
    // Failed: below stop_fraction of the peak with bonds broken, the grips half as far again
    // as at the peak (a small sample's end sphere that lets go drops the load for a moment).
    if (broken > 0 && load < spec.stop_fraction * peak &&
        strain.back() >= 1.5 * strain[static_cast<size_t>(peak_block)])
      break;
  }
  out.reached_limit = strain.empty() || strain.back() >= spec.max_strain * (1 - 1e-9) ||
                      peak_block == static_cast<int64_t>(stress.size()) - 1;
  out.broken = broken;
  out.broken_tension = tension;
  out.peak_force = peak;
  out.strength = peak / area;
  if (peak_block >= 0) out.strain_at_peak = strain[static_cast<size_t>(peak_block)];
  if (gauge && peak_block >= 0) {
    std::vector<double> fx, fy;
    for (int64_t k = 0; k < peak_block; ++k) {
      const double s = stress[static_cast<size_t>(k)];
      if (s >= 0.1 * out.strength && s <= 0.5 * out.strength) {
        fx.push_back(gauge_strain[static_cast<size_t>(k)]);
        fy.push_back(s);
      }
    }
    out.young_modulus = Slope(fx, fy);
  }
  out.cpu_s = CpuNow() - cpu0;
  return out;
}

// ---------------------------------------------------------------------------------------------
// The command.

namespace {

struct Row {
  double scale = 1;
  PlatenTestResult ucs, bt, direct;  // compression, Brazilian, direct tension
};

std::string Num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

void Check(bool ok, const std::string& option, const std::string& expected, double got) {
  if (!ok)
    throw InputError("calibrate bonds: " + option + ": expected " + expected + ", got " + Num(got));
}

std::string StopName(const PlatenTestResult& r) { return r.reached_limit ? "limit" : "failed"; }

std::string RowLine(const Row& row) {
  char text[512];
  const double ratio = row.direct.strength > 0 ? row.ucs.strength / row.direct.strength : 0;
  std::snprintf(
      text, sizeof text,
      "scale %-6g UCS %.4g MPa (%s), sigma_t %.4g MPa direct (%s), %.4g MPa Brazilian "
      "(%s), UCS/sigma_t %.3g, E %.4g MPa, broken at peak %lld/%lld and %lld/%lld, "
      "%.1f CPU s",
      row.scale, row.ucs.strength / 1e6, StopName(row.ucs).c_str(), row.direct.strength / 1e6,
      StopName(row.direct).c_str(), row.bt.strength / 1e6, StopName(row.bt).c_str(), ratio,
      row.ucs.young_modulus / 1e6, static_cast<long long>(row.ucs.broken_at_peak),
      static_cast<long long>(row.ucs.bonds), static_cast<long long>(row.bt.broken_at_peak),
      static_cast<long long>(row.bt.bonds), row.ucs.cpu_s + row.bt.cpu_s + row.direct.cpu_s);
  return text;
}

void WriteCsv(const std::string& path, const std::vector<std::string>& header,
              const dem::BondParams& bond, const std::vector<Row>& rows) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  for (const std::string& line : header) f << "# " << line << "\n";
  f << "scale,tensile_strength_pa,cohesion_pa,friction_angle_deg,modulus_pa,radius_multiplier,"
       "stiffness_ratio,ucs_pa,sigma_t_direct_pa,sigma_t_brazilian_pa,ucs_over_sigma_t_direct,"
       "e_sample_pa,strain_at_peak,"
       "broken_at_peak_ucs,broken_at_peak_bt,broken_tension_ucs,broken_ucs,bonds_ucs,bonds_bt,"
       "particles_ucs,particles_bt,steps_ucs,steps_bt,stop_ucs,stop_bt,max_overlap,time_step_s,"
       "cpu_s\n";
  for (const Row& r : rows) {
    const double ratio = r.direct.strength > 0 ? r.ucs.strength / r.direct.strength : 0;
    f << Num(r.scale) << "," << Num(bond.tensile_strength * r.scale) << ","
      << Num(bond.cohesion * r.scale) << "," << Num(bond.friction_angle / kDeg) << ","
      << Num(bond.modulus) << "," << Num(bond.radius_multiplier) << "," << Num(bond.stiffness_ratio)
      << "," << Num(r.ucs.strength) << "," << Num(r.direct.strength) << "," << Num(r.bt.strength)
      << "," << Num(ratio) << "," << Num(r.ucs.young_modulus) << "," << Num(r.ucs.strain_at_peak)
      << "," << r.ucs.broken_at_peak << "," << r.bt.broken_at_peak << "," << r.ucs.broken_tension
      << "," << r.ucs.broken << "," << r.ucs.bonds << "," << r.bt.bonds << "," << r.ucs.particles
      << "," << r.bt.particles << "," << r.ucs.steps << "," << r.bt.steps << "," << StopName(r.ucs)
      << "," << StopName(r.bt) << "," << Num(std::max(r.ucs.max_overlap, r.bt.max_overlap)) << ","
      << Num(r.ucs.time_step) << "," << Num(r.ucs.cpu_s + r.bt.cpu_s + r.direct.cpu_s) << "\n";
  }
}

}  // namespace

std::string BondCalibrationCommandLine(const BondCalibrationOptions& o) {
  std::ostringstream s;
  auto list = [](const std::vector<double>& v) {
    std::string text;
    for (const double x : v) text += (text.empty() ? "" : ",") + Num(x);
    return text;
  };
  s << "scoopsim calibrate bonds --material " << o.material;
  if (!o.materials_path.empty()) s << " --materials " << o.materials_path;
  if (o.shear_modulus > 0) s << " --shear-modulus " << Num(o.shear_modulus);
  s << " --radius " << Num(o.sample.radius) << " --spread " << Num(o.sample.spread)
    << " --particles " << o.sample.particles << " --seed " << o.sample.seed << " --modulus "
    << Num(o.bond.modulus) << " --radius-multiplier " << Num(o.bond.radius_multiplier)
    << " --stiffness-ratio " << Num(o.bond.stiffness_ratio) << " --tensile-strength "
    << Num(o.bond.tensile_strength) << " --cohesion " << Num(o.bond.cohesion)
    << " --friction-angle " << Num(o.bond.friction_angle / kDeg) << " --damping-ratio "
    << Num(o.bond.damping_ratio) << " --gap-fraction " << Num(o.gap_fraction) << " --scales "
    << list(o.scales) << " --rayleigh-fraction " << Num(o.test.rayleigh_fraction)
    << " --speed-factor " << Num(o.test.speed_factor) << " --max-strain " << Num(o.test.max_strain)
    << " --stop-fraction " << Num(o.test.stop_fraction);
  if (o.rate_check) s << " --rate-check";
  s << " -o " << o.output;
  return s.str();
}

int RunBondCalibration(const BondCalibrationOptions& given) {
  BondCalibrationOptions o = given;
  const std::string materials_path =
      o.materials_path.empty() ? std::string(SCOOPSIM_SOURCE_DIR) + "/scenes/materials.yaml"
                               : o.materials_path;
  dem::MaterialTable table;
  LoadMaterials(materials_path, &table);
  const int mi = table.Find(o.material);
  if (mi < 0) {
    std::string names;
    for (int k = 0; k < table.size(); ++k) names += (names.empty() ? "" : ", ") + table[k].name;
    throw InputError("calibrate bonds: --material: expected one of " + names + " (" +
                     materials_path + "), got '" + o.material + "'");
  }
  if (!table.has_interaction(mi, mi))
    throw InputError("calibrate bonds: --material: " + materials_path + " has no interaction " +
                     "for the pair [" + o.material + ", " + o.material + "]");
  dem::Material material = table[mi];
  Check(o.shear_modulus >= 0 && std::isfinite(o.shear_modulus), "--shear-modulus",
        "a finite number >= 0 (Pa; 0 = the material's)", o.shear_modulus);
  if (o.shear_modulus > 0) material.shear_modulus = o.shear_modulus;
  dem::BondParams& bond = o.bond;
  if (bond.modulus == 0) bond.modulus = material.YoungsModulus();

  // The options' domains, one line each.
  Check(o.sample.radius > 0 && std::isfinite(o.sample.radius), "--radius",
        "a finite number > 0 (m)", o.sample.radius);
  Check(o.sample.spread >= 0 && o.sample.spread <= 0.5, "--spread", "a number in [0, 0.5]",
        o.sample.spread);
  Check(o.sample.particles >= 50 && o.sample.particles <= 200000, "--particles",
        "a whole number in [50, 200000]", static_cast<double>(o.sample.particles));
  Check(bond.modulus > 0 && std::isfinite(bond.modulus), "--modulus", "a finite number > 0 (Pa)",
        bond.modulus);
  Check(bond.radius_multiplier > 0 && bond.radius_multiplier <= 2, "--radius-multiplier",
        "a number in (0, 2]", bond.radius_multiplier);
  Check(bond.stiffness_ratio > 0 && std::isfinite(bond.stiffness_ratio), "--stiffness-ratio",
        "a finite number > 0", bond.stiffness_ratio);
  Check(bond.tensile_strength > 0, "--tensile-strength", "a number > 0 (Pa; inf: unbreakable)",
        bond.tensile_strength);
  Check(bond.cohesion > 0, "--cohesion", "a number > 0 (Pa; inf: unbreakable)", bond.cohesion);
  Check(bond.friction_angle >= 0 && bond.friction_angle < 90 * kDeg, "--friction-angle",
        "a number in [0, 90) (deg)", bond.friction_angle / kDeg);
  Check(bond.damping_ratio >= 0 && bond.damping_ratio <= 1, "--damping-ratio", "a number in [0, 1]",
        bond.damping_ratio);
  Check(o.gap_fraction >= 0 && o.gap_fraction <= 1, "--gap-fraction", "a number in [0, 1]",
        o.gap_fraction);
  if (o.scales.empty()) throw InputError("calibrate bonds: --scales: expected one or more scales");
  for (const double s : o.scales)
    Check(s > 0 && std::isfinite(s), "--scales", "finite numbers > 0", s);
  Check(o.test.rayleigh_fraction > 0 && o.test.rayleigh_fraction <= 0.3, "--rayleigh-fraction",
        "a number in (0, 0.3]", o.test.rayleigh_fraction);
  Check(o.test.speed_factor > 0 && std::isfinite(o.test.speed_factor), "--speed-factor",
        "a finite number > 0", o.test.speed_factor);
  Check(o.test.max_strain > 0 && o.test.max_strain <= 0.5, "--max-strain", "a number in (0, 0.5]",
        o.test.max_strain);
  Check(o.test.stop_fraction > 0 && o.test.stop_fraction < 1, "--stop-fraction",
        "a number in (0, 1)", o.test.stop_fraction);
  CheckWritable(o.output);

  // The samples, made once.
  BondSampleSpec spec = o.sample;
  spec.material = material;
  spec.interaction = table.interaction(mi, mi);
  spec.threads = o.test.threads;
  const BondSample prism = MakeBondSample(spec, BondSampleShape::kPrism);
  const BondSample disk = MakeBondSample(spec, BondSampleShape::kDisk);
  const double gap = o.gap_fraction * o.sample.radius;
  PlatenTestSpec test = o.test;
  test.interaction = spec.interaction;
  test.bond = bond;
  test.gap = gap;

  std::vector<std::string> header;
  header.push_back("command: " + BondCalibrationCommandLine(o));
  header.push_back("material " + material.name + " (" + materials_path + "): density " +
                   Num(material.density) + " kg/m^3, G " + Num(material.shear_modulus) +
                   " Pa, nu " + Num(material.poisson));
  char text[512];
  std::snprintf(text, sizeof text,
                "prism %lld spheres, %.4g x %.4g x %.4g mm, solid fraction %.3f (settled in %lld "
                "steps); disk %lld spheres, D %.4g mm, t %.4g mm, solid fraction %.3f (%lld steps)",
                static_cast<long long>(prism.x.size()), prism.width * 1e3, prism.width * 1e3,
                prism.height * 1e3, prism.solid_fraction,
                static_cast<long long>(prism.settle_steps), static_cast<long long>(disk.x.size()),
                disk.diameter * 1e3, disk.thickness * 1e3, disk.solid_fraction,
                static_cast<long long>(disk.settle_steps));
  header.push_back(text);
  header.push_back("bonds between spheres closer than gap " + Num(gap) +
                   " m; strengths = scale x (tensile_strength, cohesion)");
  header.push_back(
      "loaded through gripped ends (the spheres within one diameter of each end driven at +-v/2); "
      "UCS = peak load / W^2 (the prism pushed); sigma_t direct = peak load / W^2 (the prism "
      "pulled); sigma_t Brazilian = 2 P / (pi D t) (ISRM 1978, on a disk gripped at two 30 deg "
      "flats); E_sample = least-squares slope of stress against the gauge strain (the sample's "
      "middle half) over 10-50% of UCS before the peak; strain_at_peak: the grips'");
  header.push_back(
      "grip speed v = speed_factor x min(sigma_c / E_b, max_strain) x "
      "sqrt(E_b / rho) / 100; stop: load < stop_fraction x peak after a break, the grips "
      "1.5x as far as at the peak (failed), or max_strain (limit)");
  if (!o.quiet)
    std::fprintf(stderr, "scoopsim: %s\nscoopsim: %s\n", header[1].c_str(), header[2].c_str());

  std::vector<Row> rows;
  for (const double scale : o.scales) {
    test.strength_scale = scale;
    Row row;
    row.scale = scale;
    row.ucs = RunPlatenTest(prism, test);
    PlatenTestSpec pull = test;
    pull.pull = true;
    row.direct = RunPlatenTest(prism, pull);
    row.bt = RunPlatenTest(disk, test);
    rows.push_back(row);
    std::printf("%s\n", RowLine(row).c_str());
    std::fflush(stdout);
    WriteCsv(o.output, header, bond, rows);
  }
  if (o.rate_check) {
    PlatenTestSpec slow = test;
    slow.strength_scale = o.scales.front();
    slow.speed_factor = 0.5 * test.speed_factor;
    const PlatenTestResult ucs = RunPlatenTest(prism, slow);
    slow.pull = true;
    const PlatenTestResult direct = RunPlatenTest(prism, slow);
    slow.pull = false;
    const PlatenTestResult bt = RunPlatenTest(disk, slow);
    const Row& first = rows.front();
    const auto change = [](double now, double was) { return was > 0 ? 100 * (now / was - 1) : 0; };
    std::snprintf(text, sizeof text,
                  "rate check, scale %g at half the speed: UCS %.4g MPa (%+.1f%%), sigma_t %.4g "
                  "MPa direct (%+.1f%%), %.4g MPa Brazilian (%+.1f%%), E %.4g MPa (%+.1f%%)",
                  first.scale, ucs.strength / 1e6, change(ucs.strength, first.ucs.strength),
                  direct.strength / 1e6, change(direct.strength, first.direct.strength),
                  bt.strength / 1e6, change(bt.strength, first.bt.strength),
                  ucs.young_modulus / 1e6, change(ucs.young_modulus, first.ucs.young_modulus));
    header.push_back(text);
    std::printf("%s\n", text);
    WriteCsv(o.output, header, bond, rows);
  }
  return kExitOk;
}

}  // namespace sim

#include "sim/loop/bed.h"

#include <algorithm>
#include <cmath>

#include "dem/insertion.h"
#include "sim/loop/dig.h"

namespace sim {

dem::SystemConfig MakeSystemConfig(const Scene& scene) {
  dem::SystemConfig c;
  c.gravity = scene.gravity;
  c.time_step = scene.time_step;
  c.skin = scene.skin;
  c.max_overlap_fraction = scene.max_overlap;
  c.mesh_rolling_torque = scene.dig.scoop.rolling_torque;
  const dem::Vec3 lo = scene.box_min, hi = scene.box_max;
  // The grid covers the box and some head room above its open top.
  c.domain_min = lo;
  c.domain_max = hi;
  const int wall = scene.materials.Find(scene.wall_material);
  c.planes = {
      {"floor", lo, {0, 0, 1}, wall},  {"x_min", lo, {1, 0, 0}, wall},
      {"x_max", hi, {-1, 0, 0}, wall}, {"y_min", lo, {0, 1, 0}, wall},
      {"y_max", hi, {0, -1, 0}, wall},
  };
  return c;
}

SettleReport Settle(dem::System* system, double mean_ke, double min_time, double max_time,
                    const SettleObserver& observe, int64_t check_every) {
  SettleReport r;
  const double t0 = system->time();
  const double n = std::max<double>(1.0, static_cast<double>(system->num_bodies()));
  for (;;) {
    for (int64_t k = 0; k < check_every; ++k) {
      r.status = system->Step();
      ++r.steps;
      if (!r.status.ok()) {
        r.sim_time = system->time() - t0;
        return r;
      }
    }
    r.mean_ke = system->KineticEnergy() / n;
    r.sim_time = system->time() - t0;
    if (r.mean_ke < mean_ke && r.sim_time >= min_time) {
      r.settled = true;
      return r;
    }
    if (r.sim_time >= max_time) return r;
    if (observe && !observe(*system)) return r;
  }
}

namespace {

// A rotation drawn uniformly from SO(3) (Shoemake 1992, "Uniform random rotations", Graphics Gems
// III): three uniforms, our own RNG, so a seed gives the same bed everywhere.
dem::Quat UniformRotation(dem::Rng& rng) {
  const double u1 = rng.Uniform(), u2 = 2.0 * M_PI * rng.Uniform(), u3 = 2.0 * M_PI * rng.Uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return {b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)};
}

}  // namespace

SettleReport FillAndSettle(const Scene& scene, dem::System* system, const SettleObserver& observe,
                           PourPoint* point) {
  SettleReport total;
  const BedSpec& bed = scene.bed;
  const int material = scene.materials.Find(bed.material);
  PourPoint local;
  PourPoint& at = point != nullptr ? *point : local;
  const bool resumed = at.started;
  dem::Rng rng(resumed ? at.rng : bed.seed);
  int64_t remaining = bed.count - (resumed ? at.poured : 0);
  // Clumps are poured as their bounding spheres (so no two overlap), each turned at random, at a
  // lattice pitch that gives a solid fraction of clumps of fill_fraction where it can (a resumed
  // pour's loaded bed has the template already: AddClumpTemplate reuses it).
  const bool clumps = !bed.clump.empty();
  const int shape = clumps ? system->AddClumpTemplate(bed.clump_template) : -1;
  const double fill =
      clumps ? bed.fill_fraction * 4.0 / 3.0 * M_PI * std::pow(bed.radius_max, 3) / bed.clump_volume
             : bed.fill_fraction;
  const size_t per_body = clumps ? bed.clump_template.radii.size() : 1;
  system->Reserve(static_cast<size_t>(remaining) * per_body + system->particles().size());
  auto settle = [&](double min_time, double max_time) {
    const SettleReport r = Settle(system, bed.settle_ke, min_time, max_time, observe);
    total.steps += r.steps;
    total.sim_time += r.sim_time;
    total.mean_ke = r.mean_ke;
    total.settled = r.settled;
    total.status = r.status;
    // Its settling has ended (at rest, or at max_time), not been stopped by the observer.
    at.settled = r.status.ok() && (r.settled || r.sim_time >= max_time);
    return r.status.ok();
  };
  if (resumed && !at.settled) {
    // The last layer settles on for what is left of its time.
    total.layers = at.layers;
    const double spent = system->time() - at.layer_t0;
    if (!settle(std::max(0.0, at.layer_fall - spent), bed.settle_max_time - spent)) return total;
  } else if (resumed) {
    total.layers = at.layers;  // kept between layers: the next one is poured now
  }
  while (remaining > 0) {
    if (observe && !observe(*system)) break;  // stopped between layers
    // Pour into the free part of the box above the present top of the bed.
    double top = scene.box_min.z;
    const dem::Particles& p = system->particles();
    for (size_t i = 0; i < p.size(); ++i) top = std::max(top, p.x[i].z + p.radius[i]);
    dem::Vec3 lo = scene.box_min, hi = scene.box_max;
    lo.z = top;
    const std::vector<dem::SphereSeed> seeds = dem::InsertSpheres(
        lo, hi, remaining, clumps ? bed.radius_max : bed.radius_min, bed.radius_max, fill, rng);
    if (seeds.empty()) break;  // box full: the caller reports the shortfall
    for (const dem::SphereSeed& s : seeds) {
      if (!clumps) {
        system->AddParticle(s.x, dem::Vec3{}, dem::Vec3{}, s.radius, material);
        continue;
      }
      dem::Pose pose;  // of the template frame, with the centre of mass at the seed
      pose.orientation = UniformRotation(rng);
      pose.position =
          s.x - dem::Rotate(pose.orientation, system->clump_shape(shape).center_of_mass);
      system->AddClump(shape, pose, dem::Vec3{}, dem::Vec3{}, material);
    }
    remaining -= static_cast<int64_t>(seeds.size());
    ++total.layers;
    // The layer cannot be at rest before its top has had time to fall to its bottom:
    // t = sqrt(2 h / g) for the layer's height h.
    double z_lo = seeds.front().x.z, z_hi = z_lo;
    for (const dem::SphereSeed& s : seeds) {
      z_lo = std::min(z_lo, s.x.z);
      z_hi = std::max(z_hi, s.x.z);
    }
    const double g = dem::Norm(scene.gravity);
    const double t_fall = g > 0 ? std::sqrt(2.0 * (z_hi - z_lo) / g) : 0.0;
    at = {total.layers, bed.count - remaining, rng.state(), system->time(), t_fall, true, false};
    if (!settle(t_fall, bed.settle_max_time)) break;
  }
  return total;
}

double BondSurface(const Scene& scene, const dem::Particles& particles) {
  if (scene.dig.enabled && scene.dig.surface_given) return scene.dig.surface;
  const double r_max = scene.bed.radius_max;
  const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
  return BedSurface(particles, scene.box_min + margin, scene.box_max - margin, 4 * r_max);
}

std::vector<dem::Bond> MakeBedBonds(const dem::System& system, const BondSpec& spec,
                                    double surface) {
  std::vector<dem::Bond> bonds;
  if (!spec.enabled) return bonds;
  const dem::Particles& p = system.particles();
  // Storage index of each persistent id (ids ascending with their index).
  std::vector<std::pair<int64_t, size_t>> index(p.size());
  for (size_t i = 0; i < p.size(); ++i) index[i] = {p.id[i], i};
  std::sort(index.begin(), index.end());
  const auto find = [&](int64_t id) {
    const auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(id, size_t{0}));
    return it->second;
  };
  const std::vector<std::pair<int64_t, int64_t>> pairs = system.PairsWithinGap(spec.gap);
  bonds.reserve(pairs.size());
  for (const auto& [ida, idb] : pairs) {
    const size_t a = find(ida), b = find(idb);
    const dem::Vec3 d = p.x[b] - p.x[a];
    const double distance = dem::Norm(d);
    const double ra = p.radius[a], rb = p.radius[b];
    const dem::Vec3 point = p.x[a] + (ra + 0.5 * (distance - ra - rb)) / distance * d;
    const double f = BondStrengthFactor(spec.strength_vs_depth, surface - point.z);
    if (!(f > 0)) continue;  // no cement where the law leaves no strength
    // The strengths scaled here, not by MakeBond's factor, so that .inf stays .inf.
    dem::BondParams params = spec.params;
    const auto scaled = [f](double s) { return std::isinf(s) ? s : s * f; };
    params.tensile_strength = scaled(params.tensile_strength);
    params.cohesion = scaled(params.cohesion);
    bonds.push_back(dem::MakeBond(ida, ra, idb, rb, distance, params, 1.0));
  }
  return bonds;
}

}  // namespace sim

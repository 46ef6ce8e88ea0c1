#include "sim/loop/preflight.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "dem/material.h"
#include "sim/files/bed_io.h"
#include "sim/input/trajectory.h"
#include "sim/loop/bed.h"
#include "sim/loop/dig.h"
#include "sim/loop/scoop_driver.h"

namespace sim {
namespace {

// A number with 3 (or `digits`) significant digits, for messages.
std::string Num(double v, int digits = 3) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
  return buffer;
}

// "1.5 GiB", "931 TiB": a byte count for messages.
std::string Bytes(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024 && u < 6) {
    bytes /= 1024;
    ++u;
  }
  return Num(bytes) + " " + units[u];
}

// A refusal about `key` of the scene, at its line.
[[noreturn]] void Refuse(const Scene& scene, const std::string& key, const std::string& expected,
                         const std::string& got, const std::string& note) {
  throw InputError(scene.path, SceneLine(scene, key), key, expected, got, note);
}

double PhysicalMemory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

// What the scene's bed file holds, for the checks below.
struct FileBed {
  int64_t count = 0;
  double radius_min = 0, radius_max = 0;  // [m]
  double time_step = 0;                   // [s]
  double contact_time_step = 0;           // [s] the same without the bonds' step
  double surface = 0;                     // as World::StartDig measures it [m]
  double top = 0;                         // highest particle top [m]
};

// The deepest overlap between two spheres of different bodies (clump members among themselves
// excepted) as a fraction of the smaller diameter, and the pair's indices; cells of the largest
// diameter, sorted, so a large bed takes a second at most.
struct DeepestOverlap {
  double fraction = 0;
  size_t a = 0, b = 0;
};
DeepestOverlap FindDeepestOverlap(const dem::System& system) {
  const dem::Particles& p = system.particles();
  const size_t n = p.size();
  DeepestOverlap deepest;
  if (n < 2) return deepest;
  // The body of each sphere: its clump, or itself (the id map only for a bed of clumps).
  std::vector<int64_t> body(n);
  for (size_t k = 0; k < n; ++k) body[k] = -1 - static_cast<int64_t>(k);
  const dem::Clumps& clumps = system.clumps();
  std::unordered_map<int64_t, size_t> index;
  if (clumps.size() > 0)
    for (size_t k = 0; k < n; ++k) index.emplace(p.id[k], k);
  for (size_t c = 0; c < clumps.size(); ++c) {
    for (int32_t m = clumps.first[c]; m < clumps.first[c + 1]; ++m) {
      const auto it = index.find(clumps.member[static_cast<size_t>(m)]);
      if (it != index.end()) body[it->second] = static_cast<int64_t>(c);
    }
  }
  const double r_max = *std::max_element(p.radius.begin(), p.radius.end());
  dem::Vec3 lo = p.x[0];
  for (const dem::Vec3& x : p.x)
    lo = {std::min(lo.x, x.x), std::min(lo.y, x.y), std::min(lo.z, x.z)};
  const double cell = 2 * r_max;
  const auto cell_of = [&](const dem::Vec3& x) {
    return std::array<int64_t, 3>{static_cast<int64_t>((x.x - lo.x) / cell),
                                  static_cast<int64_t>((x.y - lo.y) / cell),
                                  static_cast<int64_t>((x.z - lo.z) / cell)};
  };
  const auto key = [](int64_t i, int64_t j, int64_t k) {
    return (i * 1048576 + j) * 1048576 + k;  // cells < 2^20 a side: beds of a metre at 1 um
  };
  std::vector<std::pair<int64_t, size_t>> sorted(n);
  for (size_t k = 0; k < n; ++k) {
    const auto c = cell_of(p.x[k]);
    sorted[k] = {key(c[0], c[1], c[2]), k};
  }
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 0; k < n; ++k) {
    const auto c = cell_of(p.x[k]);
    for (int64_t di = -1; di <= 1; ++di)
      for (int64_t dj = -1; dj <= 1; ++dj)
        for (int64_t dk = -1; dk <= 1; ++dk) {
          if (c[0] + di < 0 || c[1] + dj < 0 || c[2] + dk < 0) continue;
          const int64_t want = key(c[0] + di, c[1] + dj, c[2] + dk);
          auto it =
              std::lower_bound(sorted.begin(), sorted.end(), std::pair<int64_t, size_t>{want, 0});
          for (; it != sorted.end() && it->first == want; ++it) {
            const size_t j = it->second;
            if (j <= k || body[j] == body[k]) continue;
            const dem::Vec3 d = p.x[j] - p.x[k];
            const double overlap = p.radius[j] + p.radius[k] - std::sqrt(dem::Dot(d, d));
            const double fraction = overlap / (2 * std::min(p.radius[j], p.radius[k]));
            if (fraction > deepest.fraction) deepest = {fraction, k, j};
          }
        }
  }
  return deepest;
}

// Step 1: bed.file loaded (and so checked, sim/files/bed_io.h) into a system of the scene's model,
// its radii checked against the scene's; its surface and top measured.
FileBed CheckBedFile(Scene* scene) {
  BedSpec& bed = scene->bed;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(bed.file, ec)) {
    Refuse(*scene, "bed.file", "an existing bed file (made by `scoopsim bed SCENE -o FILE`)",
           bed.file, "no such file");
  }
  dem::System system(scene->materials, MakeSystemConfig(*scene));
  LoadBed(bed.file, &system);
  const dem::Particles& p = system.particles();
  FileBed f;
  f.count = static_cast<int64_t>(p.size());
  if (f.count == 0) Refuse(*scene, "bed.file", "a bed with particles", bed.file, "it has none");
  f.radius_min = *std::min_element(p.radius.begin(), p.radius.end());
  f.radius_max = *std::max_element(p.radius.begin(), p.radius.end());
  // The radii the scene declares: bed.radius, or the spheres of the bed.clump template.
  double lo = bed.radius_min, hi = bed.radius_max;
  if (!bed.clump.empty()) {
    const std::vector<double>& r = bed.clump_template.radii;
    lo = *std::min_element(r.begin(), r.end());
    hi = *std::max_element(r.begin(), r.end());
  }
  constexpr double kTolerance = 1e-9;  // relative: radii round-trip HDF5 exactly
  if (f.radius_min < lo * (1 - kTolerance) || f.radius_max > hi * (1 + kTolerance)) {
    const std::string key = bed.clump.empty() ? "bed.radius" : "bed.clump";
    const std::string declared =
        lo == hi ? Num(lo, 6) + " m" : "[" + Num(lo, 6) + ", " + Num(hi, 6) + "] m";
    const std::string in_file = f.radius_min == f.radius_max
                                    ? Num(f.radius_min, 6) + " m"
                                    : Num(f.radius_min, 6) + " .. " + Num(f.radius_max, 6) + " m";
    Refuse(*scene, key, "radii that agree with bed.file " + bed.file + " (" + in_file + ")",
           declared, "the time step comes from " + key + ", so it must hold the file's radii");
  }
  // The time step of paper eq. 4 at the smallest declared radius, for the stiffest material
  // among the file's particles (the scene's own when the bed is of bed.material). It is that of
  // the run that poured the bed, so a run from the saved bed replays it bit for bit.
  std::vector<bool> used(static_cast<size_t>(scene->materials.size()), false);
  for (int32_t m : p.material) used[static_cast<size_t>(m)] = true;
  // The file's particles are of bed.material: a scene (or a sweep's case) that names another
  // would run the file's material under its own name.
  const int declared = scene->materials.Find(bed.material);
  for (size_t m = 0; m < used.size(); ++m) {
    if (used[m] && static_cast<int>(m) != declared) {
      Refuse(*scene, "bed.material",
             "the material of bed.file " + bed.file + "'s particles (" +
                 scene->materials[static_cast<int>(m)].name + ")",
             bed.material, "a bed file's particles keep the material they were poured with");
    }
  }
  f.time_step = scene->time_step;
  f.contact_time_step = scene->contact_time_step;
  for (size_t m = 0; m < used.size(); ++m) {
    if (!used[m]) continue;
    const double t = dem::RayleighTimeStep(lo, scene->materials[static_cast<int>(m)]);
    f.time_step = std::min(f.time_step, scene->rayleigh_fraction * t);
    f.contact_time_step = std::min(f.contact_time_step, scene->rayleigh_fraction * t);
  }
  // Its state: no sphere faster than its own radius a step (it would jump through a neighbour),
  // no two bodies overlapping past health.max_overlap (the run would stop at its first step,
  // blaming the time step; these are the file's).
  for (size_t k = 0; k < p.size(); ++k) {
    const double speed = std::sqrt(dem::Dot(p.v[k], p.v[k]));
    if (!(speed * f.time_step <= p.radius[k])) {
      Refuse(*scene, "bed.file",
             "particles slower than their radius a time step (" +
                 Num(p.radius[k] / f.time_step, 4) + " m/s for particle " +
                 std::to_string(p.id[k]) + ")",
             bed.file,
             "/particles/velocity: particle " + std::to_string(p.id[k]) + " at " + Num(speed, 4) +
                 " m/s");
    }
  }
  const DeepestOverlap deepest = FindDeepestOverlap(system);
  if (deepest.fraction > scene->max_overlap) {
    Refuse(*scene, "bed.file",
           "particles overlapping by at most health.max_overlap (" + Num(scene->max_overlap, 4) +
               " of the smaller diameter)",
           bed.file,
           "/particles/position: particles " + std::to_string(p.id[deepest.a]) + " and " +
               std::to_string(p.id[deepest.b]) + " overlap by " + Num(deepest.fraction, 4) +
               " of the smaller diameter");
  }
  // The surface and top as World::StartDig measures them.
  const double r_max = bed.radius_max;
  const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
  f.surface = BedSurface(p, scene->box_min + margin, scene->box_max - margin, 4 * r_max);
  f.top = f.surface;
  for (size_t k = 0; k < p.size(); ++k) f.top = std::max(f.top, p.x[k].z + p.radius[k]);
  return f;
}

// The key of a move of the dig's path, as the scene wrote it: "dig.trajectory.moves[4]" or
// "dig.trajectory.rotation2" (a preset's segment).
std::string MoveKey(const Move& move) { return "dig.trajectory." + move.name; }

// Step 4: the scoop's size and, pass after pass, its path against the floor and the side walls.
// `surface` is where the path's depth is measured from, `surface_from` the inputs it comes from
// (for messages). Every vertex of the mesh is placed at poses sampled no further apart than
// half the smallest sphere's radius at the path's fastest point speed (at least 400 a pass, at
// most 200,000), so a fast move through a wall and back is not stepped over.
void CheckDigPath(const Scene& scene, double surface, double clear_z,
                  const std::string& surface_from) {
  const DigSpec& dig = scene.dig;
  const dem::TriangleMesh& mesh = dig.scoop.geometry;
  dem::Vec3 lo{1e300, 1e300, 1e300}, hi = -1.0 * lo;
  for (const dem::Vec3& v : mesh.vertices) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  const dem::Vec3 size = hi - lo, box = scene.box_max - scene.box_min;
  const double scoop_size = std::max({size.x, size.y, size.z});
  const double box_size = std::max({box.x, box.y, box.z});
  if (!(scoop_size <= 10 * box_size)) {
    Refuse(scene, "dig.scoop.scale",
           "a scale that makes the scoop at most ten times the box's largest side (" +
               Num(box_size) + " m)",
           Num(dig.scoop.scale, 6), "the scoop would be " + Num(scoop_size) + " m across");
  }
  // The path as written, its move starts resolved (the same times in every pass), and the
  // fastest any vertex moves along it.
  const Trajectory path(dig.trajectory);
  const std::vector<Move>& moves = path.spec().moves;
  double fastest = 0;
  for (const Move& m : moves) {
    if (m.kind == Move::Kind::kTranslate) fastest = std::max(fastest, m.speed);
    if (m.kind != Move::Kind::kRotate) continue;
    const dem::Vec3 about = m.about_pivot ? dig.trajectory.pivot_offset : m.point;
    for (const dem::Vec3& v : mesh.vertices) {
      const dem::Vec3 d = v - about;
      fastest = std::max(fastest, m.speed * std::sqrt(dem::Dot(d, d)));
    }
  }
  const double spacing = 0.5 * scene.bed.radius_min;
  constexpr int kMinSamples = 400, kMaxSamples = 200000;
  BedContext bed{&mesh, surface, clear_z, scene.time_step, 0.0};
  // The tool path as placed per pass (whichever driver carries the scoop along it: an arm tracks
  // it), not the run's driver (MakeScoopDriver, below).
  const std::unique_ptr<KinematicDriver> driver = KinematicDriver::ForDig(dig);
  for (int pass = 1; pass <= dig.passes; ++pass) {
    const double duration = driver->BeginPass(pass, bed).duration;
    if (!std::isfinite(duration)) return;  // refused by the step count (Preflight, 3.)
    const double descent = duration - (path.end_time() - path.start_time());
    const double samples = std::clamp(fastest > 0 ? std::ceil(duration * fastest / spacing) : 0.0,
                                      double{kMinSamples}, double{kMaxSamples});
    const int n = static_cast<int>(samples);
    // The pass's level: the level scoop's lowest point once the approach is done.
    const double level = surface - pass * dig.bite_depth;
    const std::string depth = "pass " + std::to_string(pass) + " cuts " + std::to_string(pass) +
                              " x dig.bite_depth = " + Num(pass * dig.bite_depth) + " m below " +
                              surface_from + ", to z = " + Num(level) + " m";
    for (int k = 0; k <= n; ++k) {
      const double tau = duration * k / n;
      const dem::Pose pose = driver->MotionAt(tau).pose;
      for (const dem::Vec3& v : mesh.vertices) {
        const dem::Vec3 x = dem::Apply(pose, v);
        const bool below_floor = x.z < scene.box_min.z;
        const bool through_wall =
            x.z < surface && (x.x < scene.box_min.x || x.x > scene.box_max.x ||
                              x.y < scene.box_min.y || x.y > scene.box_max.y);
        if (!below_floor && !through_wall) continue;
        const std::string at = "pass " + std::to_string(pass) + " taking the scoop to [" +
                               Num(x.x) + ", " + Num(x.y) + ", " + Num(x.z) + "] m " + Num(tau) +
                               " s into the pass";
        // The move under way then (none during the descent to the path's start).
        const double t = tau - descent + path.start_time();
        const Move* move = nullptr;
        for (const Move& m : moves)
          if (tau >= descent && m.start <= t) move = &m;
        // A move the scene wrote in dig.trajectory.moves is blamed for where it takes the
        // scoop (the first one places it: dig.trajectory.start, or the pass's depth); a
        // preset's segments are not the scene's to change.
        const bool blame_move =
            move != nullptr && move != &moves.front() && move->name.rfind("moves[", 0) == 0;
        if (below_floor) {
          if (blame_move && level >= scene.box_min.z) {
            // The pass's level is above the floor: the move takes the scoop below it.
            Refuse(scene, MoveKey(*move),
                   "a move that keeps the scoop above the floor (box.min z = " +
                       Num(scene.box_min.z) + " m)",
                   at, depth + "; " + move->name + " goes " + Num(level - x.z) + " m below that");
          }
          Refuse(scene, "dig.bite_depth",
                 "a path that keeps the scoop above the floor (box.min z = " +
                     Num(scene.box_min.z) + " m)",
                 at, depth + "; lower dig.bite_depth or dig.passes, or raise the bed");
        }
        Refuse(scene, blame_move ? MoveKey(*move) : "dig.trajectory.start",
               "a path that keeps the scoop inside the side walls below the bed's surface", at,
               surface_from + (blame_move ? "; the move carries the scoop through a side wall"
                                          : "; move dig.trajectory.start or widen the box"));
      }
    }
  }
}

// The inputs of the scene's time step, for messages: "time_step.rayleigh_fraction 0.25 x the
// Rayleigh time (paper eq. 4) of bed.radius 0.008 m, material snow (scenes/materials.yaml:
// density 300 kg/m^3, shear_modulus ... Pa, poisson ...)".
std::string TimeStepInputs(const Scene& scene) {
  const BedSpec& bed = scene.bed;
  const int index = scene.materials.Find(bed.material);
  std::string material = bed.material;
  if (index >= 0) {
    const dem::Material& m = scene.materials[index];
    material += " (" + scene.materials_path + ": density " + Num(m.density) +
                " kg/m^3, shear_modulus " + Num(m.shear_modulus) + " Pa, poisson " +
                Num(m.poisson) + ")";
  }
  return "time_step.rayleigh_fraction " + Num(scene.rayleigh_fraction) +
         " x the Rayleigh time (paper eq. 4) of " +
         (bed.clump.empty() ? "bed.radius " : "bed.clump's smallest sphere ") +
         Num(bed.radius_min) + " m, material " + material;
}

}  // namespace

std::string TimeStepLine(const Scene& scene) {
  std::string line = "time step " + Num(scene.time_step, 4) + " s, set by the ";
  if (std::string(TimeStepRule(scene)) == "bond") {
    return line + "bonds (dem::BondCriticalStep of bed.bonds at the smallest sphere, " +
           Num(scene.bond_time_step, 4) + " s < " + TimeStepInputs(scene) + ", " +
           Num(scene.contact_time_step, 4) + " s)";
  }
  line += "contact (" + TimeStepInputs(scene) + ")";
  if (scene.bond_time_step > 0)
    line += "; the bonds' critical step is " + Num(scene.bond_time_step, 4) + " s";
  return line;
}

RunForecast Preflight(Scene* scene, Work work) {
  BedSpec& bed = scene->bed;
  RunForecast f;
  const bool from_file = work == Work::kRun && !bed.file.empty();
  FileBed file;
  f.contact_time_step = scene->contact_time_step;
  if (from_file) {
    file = CheckBedFile(scene);
    scene->time_step = file.time_step;
    f.contact_time_step = file.contact_time_step;
  }
  f.time_step = scene->time_step;
  f.time_step_rule = TimeStepRule(*scene);
  // `scoopsim bed` pours bed.count whatever bed.file says (LoadScene left it to here).
  if (work == Work::kBed && !bed.file.empty()) CheckBedFitsTheBox(*scene);

  // 2. Memory.
  // In floating point: bed.count x spheres per clump may not fit an int64_t.
  const double per_body =
      bed.clump.empty() ? 1.0 : static_cast<double>(bed.clump_template.radii.size());
  const double particles =
      from_file ? static_cast<double>(file.count) : static_cast<double>(bed.count) * per_body;
  f.bytes = particles * kBytesPerParticle;
  f.memory = PhysicalMemory();
  if (f.memory > 0 && f.bytes > f.memory) {
    Refuse(*scene, from_file ? "bed.file" : "bed.count",
           "a bed that fits in this machine's memory (" + Bytes(f.memory) + ")",
           from_file ? bed.file + " of " + std::to_string(file.count) + " particles"
                     : std::to_string(bed.count),
           "it would need about " + Bytes(f.bytes) + " at ~" + Bytes(kBytesPerParticle) +
               " per particle");
  }
  f.particles = static_cast<int64_t>(std::min(particles, 9e18));  // within the cast's range

  // 4 first for a dig (its planned time is needed for 3): the surface and the path.
  const double r_max = bed.radius_max;
  double clear_z = 0;
  if (scene->dig.enabled) {
    f.surface = bed.settled_height + scene->box_min.z;
    f.surface_estimated = true;
    clear_z = f.surface + 3 * r_max;  // the estimated top of the bed, clear by 2 r_max
    const dem::Vec3 box = scene->box_max - scene->box_min;
    std::string surface_from =
        "the surface at z = " + Num(f.surface) + " m estimated from bed.count " +
        std::to_string(bed.count) +
        (bed.clump.empty() ? " spheres of bed.radius " + Num(bed.radius_max)
                           : " clumps of bed.clump " + bed.clump + " (" + Num(bed.radius_max)) +
        " m" + (bed.clump.empty() ? "" : ")") + " settled over the box's " + Num(box.x) + " x " +
        Num(box.y) + " m floor";
    if (from_file) {
      f.surface = file.surface;
      f.surface_estimated = false;
      clear_z = file.top + 2 * r_max;
      surface_from = "the surface of bed.file " + bed.file + " at z = " + Num(f.surface) + " m";
    }
    if (scene->dig.surface_given) {
      f.surface = scene->dig.surface;
      f.surface_estimated = false;
      surface_from = "dig.surface (z = " + Num(f.surface) + " m)";
    }
    CheckDigPath(*scene, f.surface, clear_z, surface_from);
  }

  // What a pass's driver knows of the bed (a dig's).
  const BedContext context{&scene->dig.scoop.geometry, f.surface, clear_z, scene->time_step, 0.0};

  // 3. Steps: settling (a bed still to be poured) and the run.
  f.simulated = from_file ? 0.0 : bed.settle_max_time;
  std::string time_key = "bed.settle.max_time";
  if (work == Work::kRun) {
    if (scene->dig.enabled) {
      // The tool path's own length, cheap: an arm's (slowed) plan waits until this is sane.
      const std::unique_ptr<KinematicDriver> driver = KinematicDriver::ForDig(scene->dig);
      for (int pass = 1; pass <= scene->dig.passes; ++pass)
        f.simulated += driver->PlannedDuration(pass, context);
      time_key = "dig";
    } else {
      f.simulated += scene->duration;
      time_key = "duration";
    }
  }
  f.steps = f.simulated / f.time_step;
  if (!(f.steps <= kMaxSteps)) {
    // Blame the time step when the run would fit at the usual fraction of 0.2, else the time.
    const double usual_steps = f.steps * scene->rayleigh_fraction / 0.2;
    const bool blame_step = usual_steps <= kMaxSteps;
    const std::string key = blame_step ? "time_step.rayleigh_fraction" : time_key;
    const bool finite = std::isfinite(f.steps);
    // The step's own inputs named (a bed file's smallest sphere may set it lower).
    const std::string step = "steps of " + Num(f.time_step) + " s (" +
                             (from_file ? "at most " : "") + TimeStepInputs(*scene) + ")";
    Refuse(*scene, key, "a run of at most " + Num(kMaxSteps) + " steps",
           blame_step ? Num(scene->rayleigh_fraction, 6)
                      : (finite ? Num(f.simulated) + " s simulated" : "a run without an end"),
           finite ? "about " + Num(f.steps) + " " + step + " for " + Num(f.simulated) +
                        " s simulated: the run could never end"
                  : "its planned time has no end");
  }
  // A bond that forces a step 10x or more smaller than the contact's (issue 44): its cost, the
  // steps and particle-steps against the unbonded run's.
  if (scene->bond_time_step > 0 && f.time_step * kCostlyBondStepRatio <= f.contact_time_step) {
    const double unbonded = f.simulated / f.contact_time_step;
    const double n = static_cast<double>(f.particles);
    f.bond_note = SceneNote(
        *scene, "bed.bonds.modulus",
        "bed.bonds: the bonds' critical step " + Num(f.time_step) + " s is " +
            Num(f.contact_time_step / f.time_step) + " x smaller than the contact's " +
            Num(f.contact_time_step) + " s: about " + Num(f.steps) + " steps (" + Num(f.steps * n) +
            " particle-steps) against " + Num(unbonded) + " (" + Num(unbonded * n) +
            ") unbonded; a lower bed.bonds.modulus or a larger bed.radius costs less");
  }
  // The scene's own driver plans each pass once the run's length is known to be sane (above, on
  // the tool path's own length; an arm's plan samples its path every 10 ms): an arm's path out
  // of its reach is refused here, before any work (ArmDriver throws InputError naming arm.base),
  // and so is a wrench table that does not cover the dig (TableWrench).
  if (work == Work::kRun && scene->dig.enabled) {
    const std::unique_ptr<ScoopDriver> driver = MakeScoopDriver(*scene, /*announce=*/false);
    for (int pass = 1; pass <= scene->dig.passes; ++pass) driver->PlannedDuration(pass, context);
  }
  return f;
}

}  // namespace sim

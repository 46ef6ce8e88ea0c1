#include "sim/preflight.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "dem/material.h"
#include "sim/arm_driver.h"
#include "sim/bed.h"
#include "sim/bed_io.h"
#include "sim/dig.h"
#include "sim/scoop_driver.h"

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
  double surface = 0;                     // as World::StartDig measures it [m]
  double top = 0;                         // highest particle top [m]
};

// Step 1: bed.file loaded (and so checked, sim/bed_io.h) into a system of the scene's model, its
// radii checked against the scene's; its surface and top measured.
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
  for (size_t m = 0; m < used.size(); ++m) {
    if (!used[m]) continue;
    const double t = dem::RayleighTimeStep(lo, scene->materials[static_cast<int>(m)]);
    f.time_step = std::min(f.time_step, scene->rayleigh_fraction * t);
  }
  // The surface and top as World::StartDig measures them.
  const double r_max = bed.radius_max;
  const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
  f.surface = BedSurface(p, scene->box_min + margin, scene->box_max - margin, 4 * r_max);
  f.top = f.surface;
  for (size_t k = 0; k < p.size(); ++k) f.top = std::max(f.top, p.x[k].z + p.radius[k]);
  return f;
}

// Step 4: the scoop's size and, pass after pass, its path against the floor and the side walls.
// The path is sampled at kSamples poses per pass; every vertex of the mesh is placed at each.
void CheckDigPath(const Scene& scene, double surface, double clear_z, bool estimated) {
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
  const std::string where =
      estimated ? "the surface estimated from bed.count at z = " + Num(surface) + " m"
                : "the surface at z = " + Num(surface) + " m";
  constexpr int kSamples = 400;
  BedContext bed{&mesh, surface, clear_z, scene.time_step, 0.0};
  const std::unique_ptr<KinematicDriver> driver = KinematicDriver::ForDig(dig);
  for (int pass = 1; pass <= dig.passes; ++pass) {
    const double duration = driver->BeginPass(pass, bed).duration;
    if (!std::isfinite(duration)) return;  // refused by the step count (Preflight, 3.)
    for (int k = 0; k <= kSamples; ++k) {
      const double tau = duration * k / kSamples;
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
        if (below_floor) {
          Refuse(scene, "dig.bite_depth",
                 "a path that keeps the scoop above the floor (box.min z = " +
                     Num(scene.box_min.z) + " m)",
                 at,
                 "it cuts " + Num(pass * dig.bite_depth) + " m below " + where +
                     "; lower dig.bite_depth or dig.passes, or raise the bed");
        }
        Refuse(scene, "dig.trajectory.start",
               "a path that keeps the scoop inside the side walls below the bed's surface", at,
               where + "; move dig.trajectory.start or widen the box");
      }
    }
  }
}

}  // namespace

RunForecast Preflight(Scene* scene, Work work) {
  BedSpec& bed = scene->bed;
  RunForecast f;
  const bool from_file = work == Work::kRun && !bed.file.empty();
  FileBed file;
  if (from_file) {
    file = CheckBedFile(scene);
    scene->time_step = file.time_step;
  }
  f.time_step = scene->time_step;

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
  f.particles = static_cast<int64_t>(particles);

  // 4 first for a dig (its planned time is needed for 3): the surface and the path.
  const double r_max = bed.radius_max;
  double clear_z = 0;
  if (scene->dig.enabled) {
    f.surface = bed.settled_height + scene->box_min.z;
    f.surface_estimated = true;
    clear_z = f.surface + 3 * r_max;  // the estimated top of the bed, clear by 2 r_max
    if (from_file) {
      f.surface = file.surface;
      f.surface_estimated = false;
      clear_z = file.top + 2 * r_max;
    }
    if (scene->dig.surface_given) {
      f.surface = scene->dig.surface;
      f.surface_estimated = false;
    }
    CheckDigPath(*scene, f.surface, clear_z, f.surface_estimated);
  }

  // 3. Steps: settling (a bed still to be poured) and the run.
  f.simulated = from_file ? 0.0 : bed.settle_max_time;
  std::string time_key = "bed.settle.max_time";
  if (work == Work::kRun) {
    if (scene->dig.enabled) {
      const BedContext context{&scene->dig.scoop.geometry, f.surface, clear_z, scene->time_step,
                               0.0};
      const std::unique_ptr<KinematicDriver> driver = KinematicDriver::ForDig(scene->dig);
      for (int pass = 1; pass <= scene->dig.passes; ++pass)
        f.simulated += driver->PlannedDuration(pass, context);
      // The arm's plan of each pass (IK): a path out of its reach is refused here, before any
      // work (ArmDriver throws InputError naming arm.base).
      if (scene->arm.enabled && !scene->arm.table_driven && scene->arm.model) {
        ArmDriver arm(*scene, /*announce=*/false);
        for (int pass = 1; pass <= scene->dig.passes; ++pass) arm.PlannedDuration(pass, context);
      }
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
    Refuse(*scene, key, "a run of at most " + Num(kMaxSteps) + " steps",
           blame_step ? Num(scene->rayleigh_fraction, 6)
                      : (finite ? Num(f.simulated) + " s simulated" : "a run without an end"),
           finite ? "about " + Num(f.steps) + " steps of " + Num(f.time_step) + " s for " +
                        Num(f.simulated) + " s simulated: the run could never end"
                  : "its planned time has no end");
  }
  return f;
}

}  // namespace sim

// The commands behind the CLI: make a bed, run a scene, benchmark. Each returns a process exit
// status; bad input throws sim::InputError (the CLI prints it and exits 2).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/world_view.h"

namespace sim {

// What a dig run measured, for callers that want numbers rather than the HDF5 file (tests,
// studies). Magnitudes of the wrench in the world frame about the scoop CoM, over all rows.
struct DigSummary {
  double peak_force = 0;               // max |F| [N]
  double mean_force = 0;               // mean |F| over the rows after first contact [N]
  double peak_torque = 0;              // max |T| [N m]
  std::vector<double> collected_mass;  // per pass [kg]
  int64_t particles = 0;               // at the start of the dig
  int64_t steps = 0;
  double simulated = 0;  // [s]
};

struct RunOptions {
  int threads = 0;     // 0 = all cores
  std::string output;  // output HDF5 path
  bool quiet = false;  // no progress output
  // Frames: when set, RunScene calls on_frame at t0 and then every frame_every simulated seconds
  // (0 = at every output interval), from the main thread, with no OpenMP region active.
  FrameCallback on_frame;
  double frame_every = 0;             // [s]
  DigSummary* dig_summary = nullptr;  // filled by a dig run when set
};

// `scoopsim bed SCENE -o BED.h5`: fill the scene's box, settle, save the bed.
int MakeBed(const Scene& scene, const RunOptions& options);

// `scoopsim run SCENE -o OUT.h5`: load (or make) the bed and run for scene.duration.
int RunScene(const Scene& scene, const RunOptions& options);

struct BenchSettleOptions {
  int64_t particles = 50000;
  int64_t steps = 2000;
  int threads = 0;
  std::string cache_dir;  // where the settled bed is cached; "" = <source>/bench/cache
};
// `scoopsim bench settle`: prints one JSON line (particles, steps, threads, wall_s,
// particle_steps_per_s, contacts_per_particle, peak_rss_mb, state_hash).
int BenchSettle(const BenchSettleOptions& options);

}  // namespace sim

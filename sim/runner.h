// The commands behind the CLI: make a bed, run a scene, benchmark. Each returns a process exit
// status; bad input throws sim::InputError (the CLI prints it and exits 2).
#pragma once

#include <string>

#include "sim/scene.h"
#include "sim/world_view.h"

namespace sim {

struct RunOptions {
  int threads = 0;     // 0 = all cores
  std::string output;  // output HDF5 path
  bool quiet = false;  // no progress output
  // Frames: when set, RunScene calls on_frame at t0 and then every frame_every simulated seconds
  // (0 = at every output interval), from the main thread, with no OpenMP region active.
  FrameCallback on_frame;
  double frame_every = 0;  // [s]
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

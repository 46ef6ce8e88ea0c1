// Beds: fill a box with a scene's particles (random non-overlapping insertion, poured in layers
// when the box cannot hold them all at once) and let them settle.
#pragma once

#include <cstdint>
#include <functional>

#include "dem/system.h"
#include "sim/files/bed_io.h"
#include "sim/input/scene.h"

namespace sim {

// Model of a scene: materials, gravity, step, walls (floor + four sides of the box), grid.
dem::SystemConfig MakeSystemConfig(const Scene& scene);

struct SettleReport {
  bool settled = false;  // mean kinetic energy per particle fell below the threshold
  double mean_ke = 0;    // at the end [J]
  double sim_time = 0;   // simulated time spent [s]
  int64_t steps = 0;
  int layers = 0;          // insertion layers poured
  dem::StepStatus status;  // first bad step, if any
};

// Called every few hundred steps with the system, for progress output and stop requests;
// return false to stop early.
using SettleObserver = std::function<bool(const dem::System&)>;

// Pours scene.bed into the (empty or partly filled) system and settles it. With `point`, it
// keeps *point up to date; a started *point (a pour saved mid-way and loaded back) is resumed:
// the last layer settles on from where it was (unless it had settled), then the rest is poured.
// Resumed from the whole state the system had when *point was taken (dem::System::SaveState),
// between two of the settling checks, which is where the observer is called, the pour goes on
// bit for bit as it would have without the stop.
SettleReport FillAndSettle(const Scene& scene, dem::System* system, const SettleObserver& observe,
                           PourPoint* point = nullptr);

// Steps until the mean kinetic energy per particle is below `mean_ke` (checked every
// `check_every` steps, and only after `min_time`: particles poured at rest start below any
// threshold) or `max_time` of simulated time has passed.
SettleReport Settle(dem::System* system, double mean_ke, double min_time, double max_time,
                    const SettleObserver& observe, int64_t check_every = 200);

}  // namespace sim

// Beds: fill a box with a scene's particles (random non-overlapping insertion, poured in layers
// when the box cannot hold them all at once) and let them settle.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

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

// Bonds (issue 44, key bed.bonds; dem/bond.h).
//
// The bed's free surface the bonds' depths are measured from [m]: dig.surface when the scene
// gives it, else the surface the dig would measure (sim/loop/dig.h BedSurface over the box less
// 4 r_max at each wall, columns of 4 r_max), so bond depth and bite depth share one datum.
double BondSurface(const Scene& scene, const dem::Particles& particles);

// The bonds bed.bonds makes in `system`: one per dem::System::PairsWithinGap(gap) pair, in its
// (sorted) order, its three strengths scaled by BondStrengthFactor of the depth of its contact
// point below `surface`. The contact point lies on the line of centres, halfway across the gap
// (or the overlap) between the two surfaces: x_a + n (r_a + (|x_b - x_a| - r_a - r_b) / 2). A
// pair where f = 0 (the linear law past its zero, a table's 0) gets no bond; a strength of .inf
// stays infinite at any depth.
std::vector<dem::Bond> MakeBedBonds(const dem::System& system, const BondSpec& spec,
                                    double surface);

}  // namespace sim

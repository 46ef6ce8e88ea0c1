// Checks made once a scene is loaded and before any work (no bed poured or loaded, no step
// taken): what the scene asks of the run and of this machine. LoadScene checks each value on its
// own; these check what follows from them together and from the files they name: a bed file's
// contents, the time step it implies, the number of steps and the memory the run needs, and the
// dig's path against the box. Each refusal is one sim::InputError naming the scene's file, line
// and key, so that a run that could never end, never fit in memory, or would drive the scoop into
// the floor is refused at once rather than hours in.
#pragma once

#include <cstdint>
#include <string>

#include "sim/input/scene.h"

namespace sim {

// What a command will do with the scene.
enum class Work {
  kBed,  // `scoopsim bed`: pour and settle a bed (bed.file is not read: it may be the output)
  kRun,  // `scoopsim run`, a sweep's case, `scoopsim check`: load bed.file or pour a bed, then
         // the dig or the scene's duration
};

// A run may take at most this many steps: at the fastest a step takes ~10 us (a bed of a few
// hundred particles), so 1e10 steps is more than a day of wall time at best.
constexpr double kMaxSteps = 1e10;
// Memory a run needs per particle [B], measured on `bench settle` (peak RSS at 20k and 80k
// particles; the particle arrays, neighbour and contact lists, the snapshot buffers), rounded up.
constexpr double kBytesPerParticle = 1024;

// `scoopsim check` reports bonds whose critical step is this many times smaller than the
// contact's, or more (issue 44).
constexpr double kCostlyBondStepRatio = 10;

// The run as Preflight foresees it.
struct RunForecast {
  int64_t particles = 0;  // spheres at the start (a clump bed: clumps x spheres per clump)
  double time_step = 0;   // [s]
  double simulated = 0;   // simulated time: settling (up to bed.settle.max_time) and the run [s]
  double steps = 0;       // simulated / time_step
  double contact_time_step = 0;  // [s] the step without the bonds (rayleigh_fraction x t_R)
  const char* time_step_rule = "contact";  // "contact" or "bond" (sim::TimeStepRule)
  // One line ("FILE:LINE: bed.bonds: ...") when the bonds force a step kCostlyBondStepRatio or
  // more times smaller than the contact's: both steps and the run's steps and particle-steps
  // against the unbonded run's. "" otherwise.
  std::string bond_note;
  double bytes = 0;                // memory the particles need, estimated [B]
  double memory = 0;               // physical memory of this machine [B]
  double surface = 0;              // world z of the bed's free surface (a dig) [m]
  bool surface_estimated = false;  // from bed.count (a bed still to be poured), else measured or
                                   // given (dig.surface)
};

// Checks the scene for `work`, in this order, and throws sim::InputError at the first refusal:
//  1. bed.file (kRun): its particles finite and inside the box, its radii within those bed.radius
//     (or bed.clump) declares, so that the time step of paper eq. 4 at the declared smallest
//     radius is never too large for the bed's own particles. It is lowered (scene->time_step)
//     when the file's particles are of a stiffer material than bed.material.
//  2. The particles fit in this machine's physical memory (the need is stated).
//  3. The run takes at most kMaxSteps steps (the estimate is stated).
//  4. A dig: the scoop (mesh x dig.scoop.scale) is not larger than ten times the box, and its
//     path, pass after pass, keeps every vertex above the floor and, below the bed's surface,
//     inside the side walls. The surface is given, measured on bed.file, or estimated from
//     bed.count; World::StartDig places the passes on the measured one.
RunForecast Preflight(Scene* scene, Work work);

// One line on the scene's time step and the rule that set it: "time step 1.2e-07 s, set by the
// bonds (... < ...)" or "..., set by the contact (time_step.rayleigh_fraction ...)".
std::string TimeStepLine(const Scene& scene);

}  // namespace sim

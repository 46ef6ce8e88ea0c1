// Progress of a long run on stderr: a live line (percent, simulated time, ETA, particle-steps/s)
// when stderr is a terminal, a plain log line every `log_period` seconds otherwise.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "dem/system.h"

namespace sim {

class Progress {
 public:
  // `label` starts each line; `total_time` is the simulated time of the whole run [s].
  Progress(std::string label, double total_time, bool quiet = false, double log_period = 10.0);
  // Call every step or every few steps: sim_time [s], particle_steps done so far.
  void Update(double sim_time, int64_t particle_steps);
  // Final line (newline on a terminal).
  void Finish(double sim_time, int64_t particle_steps);

 private:
  std::string label_;
  double total_time_;
  bool quiet_;
  bool tty_;
  double log_period_;
  std::chrono::steady_clock::time_point start_, last_print_;
};

// The phase times spent between two readings of System::phase_times().
dem::PhaseTimes PhasesSince(const dem::PhaseTimes& now, const dem::PhaseTimes& before);
// One line of where `wall` seconds went, phase by phase with their shares, "other" being what no
// phase holds (output, trajectory, bookkeeping between steps): "pairs 612.3 s (55.1%), ...".
std::string PhaseBreakdown(const dem::PhaseTimes& phases, double wall);
// The same as JSON members, in milliseconds a step: "\"ms_pairs\":1.234,...".
std::string PhaseJson(const dem::PhaseTimes& phases, double wall, double steps);

}  // namespace sim

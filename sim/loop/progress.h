// Progress of a long run on stderr: a live line (percent, simulated time, ETA, particle-steps/s)
// when stderr is a terminal, a plain log line otherwise (the first after about a second, then
// every `log_period` seconds). Status lines go through Status(), which never glues onto a live
// line. The ETA is the mean of the simulated time left at the rate of the recent past (the last
// quarter of the elapsed time, at least 2 s) and at the whole run's rate: a dig's cost per
// simulated second changes as the scoop enters and leaves the bed, which the recent rate follows
// late and the whole run's rate not at all.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dem/system.h"

namespace sim {

// "1:02:03" or "2:03" for a duration in seconds; "--:--" when unknown: not finite, negative or
// beyond 116 days (an estimate that far out is no time anyone will wait for).
std::string Clock(double seconds);

class Progress {
 public:
  // `label` starts each line; `total_time` is the simulated time of the whole run [s].
  // `wall_clock` gives seconds (a test's fake clock); by default std::chrono::steady_clock.
  Progress(std::string label, double total_time, bool quiet = false, double log_period = 10.0,
           std::function<double()> wall_clock = nullptr);
  // The run goes on from a kept state (a checkpoint, a kept pour) at `sim_time` with
  // `particle_steps` already done: the percent and the time shown are the whole run's, the rate
  // and the ETA only this sitting's work. Call before the first Update.
  void Begin(double sim_time, int64_t particle_steps);
  // Call every step or every few steps: sim_time [s], particle_steps done so far.
  void Update(double sim_time, int64_t particle_steps);
  // Final line (newline on a terminal); `done`: the run reached its end (shown as 100%).
  void Finish(double sim_time, int64_t particle_steps, bool done = true);

  // The run may end before total_time (a pour ends once the bed has settled): the ETA is then
  // an upper bound and shown as "ETA <= m:ss".
  void set_open_ended(bool open_ended) { open_ended_ = open_ended; }
  // The times given count from `clock_start` on the run's clock (a dig's from its start): the
  // line shows them on the run's clock, "t 0.41/1.41 s" (README "One clock").
  void set_clock_start(double clock_start) { clock_start_ = clock_start; }

  // Estimated wall seconds left at the last Update (NaN when unknown), for tests and logs.
  double eta() const { return eta_; }

 private:
  struct Sample {
    double elapsed, sim_time;
  };
  std::string label_;
  double total_time_;
  bool quiet_;
  bool tty_;
  double log_period_;
  bool printed_ = false;
  bool open_ended_ = false;
  double eta_;
  double clock_start_ = 0;       // the run's clock at sim_time 0 [s]
  double sim0_ = 0;              // simulated time at Begin [s]
  int64_t steps0_ = 0;           // particle-steps at Begin
  std::vector<Sample> samples_;  // (elapsed, sim_time) about every 0.1 s, for the recent rate
  std::function<double()> wall_clock_;
  double start_, last_print_;  // wall_clock_ readings [s]
};

// printf to stderr for status lines: clears a live progress line first, so a message never
// glues onto it (the line is redrawn at its next update).
void Status(const char* format, ...) __attribute__((format(printf, 1, 2)));

// The phase times spent between two readings of System::phase_times().
dem::PhaseTimes PhasesSince(const dem::PhaseTimes& now, const dem::PhaseTimes& before);
// One line of where `wall` seconds went, phase by phase with their shares, "other" being what no
// phase holds (output, trajectory, bookkeeping between steps): "pairs 612.3 s (55.1%), ...".
std::string PhaseBreakdown(const dem::PhaseTimes& phases, double wall);
// The same as JSON members, in milliseconds a step: "\"ms_pairs\":1.234,...".
std::string PhaseJson(const dem::PhaseTimes& phases, double wall, double steps);

}  // namespace sim

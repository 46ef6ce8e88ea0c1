// The thread governor: how many worker threads the next step uses. Results are bit-identical on
// any thread count (docs/dem.md, "Determinism"), so the count may change between any two
// steps; the governor changes it when measurement says another count is faster, as when another
// process holds one of the cores and every barrier waits for the descheduled thread
// (docs/dem.md, "A busy core"). Pure logic over the step times it is given: no clock of its
// own, so tests feed it made-up times.
#pragma once

#include <cstdint>

namespace dem {

struct GovernorConfig {
  // A probe compares the current count c with a neighbour (c - 1, or c + 1 back towards the
  // configured count) in four windows of as many steps each, c, other, other, c (a slow drift
  // of the step's cost cancels); the first window lasts at least this long [s].
  double window = 0.02;
  // Wall time [s] at the current count before the first probe, and the interval between probes
  // after a probe that moved the count; doubled after each probe that kept it, up to max_interval.
  double first_interval = 0.05;
  double interval = 2.0;
  double max_interval = 60.0;
  // The neighbour count is taken only when its mean step is faster than this fraction of the
  // current count's (hysteresis against noise).
  double switch_below = 0.97;
  // A probe ends early, keeping the current count, once the neighbour's first window has taken
  // this many times the current count's: a count 20x slower (spinning threads on a loaded host)
  // then costs a probe at most this much. Likewise a neighbour this many times faster is taken
  // after its first window.
  double give_up_above = 1.5;
};

class ThreadGovernor {
 public:
  // threads: the configured count, the most the governor uses (>= 1).
  explicit ThreadGovernor(int threads, GovernorConfig config = GovernorConfig());

  // The worker count for the coming step.
  int threads() const { return probing_ ? window_threads_[window_] : current_; }
  // After each step: its wall time [s] and whether it rebuilt the neighbour list (a rebuild step
  // costs many plain steps and comes when the data says, so probes leave it out).
  void Record(double seconds, bool rebuilt);

  int configured() const { return configured_; }
  int current() const { return current_; }  // the count between probes
  int64_t probes() const { return probes_; }
  int64_t switches() const { return switches_; }
  int64_t steps() const { return steps_; }              // steps recorded
  int64_t steps_fewer() const { return steps_fewer_; }  // ... on fewer than configured()

 private:
  void StartProbe();
  void EndProbe(bool gave_up);  // gave_up: the neighbour was far slower

  GovernorConfig config_;
  int configured_;
  int current_;
  double since_probe_ = 0;  // wall time since the last probe ended [s]
  double next_probe_;       // ... when the next starts [s]
  double interval_;         // the interval after the coming probe if it keeps the count [s]
  bool probing_ = false;
  int window_ = 0;               // 0..3
  int window_threads_[4] = {};   // the count of each window
  int64_t window_steps_ = 0;     // steps of each window (set by the first)
  int64_t steps_in_window_ = 0;  // steps so far in this window
  double window_elapsed_ = 0;    // wall time so far in this window [s]
  double first_elapsed_ = 0;     // wall time of the first window [s]
  double sum_[2] = {0, 0};       // plain steps' time at (current, other) [s]
  int64_t count_[2] = {0, 0};    // plain steps at (current, other)
  bool probe_down_ = true;       // direction of the next probe when both are possible
  int64_t probes_ = 0;
  int64_t switches_ = 0;
  int64_t steps_ = 0;
  int64_t steps_fewer_ = 0;
};

}  // namespace dem

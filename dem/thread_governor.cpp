// The thread governor (dem/thread_governor.h): probes a neighbouring thread count now and then
// and keeps the faster.
#include "dem/thread_governor.h"

#include <algorithm>

namespace dem {

ThreadGovernor::ThreadGovernor(int threads, GovernorConfig config)
    : config_(config),
      configured_(std::max(1, threads)),
      current_(configured_),
      next_probe_(config.first_interval),
      interval_(config.interval) {}

void ThreadGovernor::StartProbe() {
  // Down while the current count is not 1, back up while it is below the configured count;
  // both ways possible: alternately.
  const bool can_down = current_ > 1, can_up = current_ < configured_;
  if (!can_down && !can_up) {  // one thread configured: nothing to choose
    since_probe_ = 0;
    next_probe_ = 1e300;
    return;
  }
  const bool down = can_down && (!can_up || probe_down_);
  probe_down_ = !probe_down_;
  const int other = down ? current_ - 1 : current_ + 1;
  window_threads_[0] = window_threads_[3] = current_;
  window_threads_[1] = window_threads_[2] = other;
  probing_ = true;
  window_ = 0;
  window_steps_ = 0;
  steps_in_window_ = 0;
  window_elapsed_ = 0;
  sum_[0] = sum_[1] = 0;
  count_[0] = count_[1] = 0;
}

void ThreadGovernor::EndProbe(bool gave_up) {
  probing_ = false;
  ++probes_;
  const int other = window_threads_[1];
  const bool measured = !gave_up && count_[0] > 0 && count_[1] > 0;
  // Mean plain step at each count (cross-multiplied: no division by a zero count).
  if (measured && sum_[1] * static_cast<double>(count_[0]) <
                      config_.switch_below * sum_[0] * static_cast<double>(count_[1])) {
    current_ = other;
    ++switches_;
    interval_ = config_.interval;
  } else {
    interval_ = std::min(2.0 * interval_, config_.max_interval);
  }
  since_probe_ = 0;
  next_probe_ = interval_;
}

void ThreadGovernor::Record(double seconds, bool rebuilt) {
  ++steps_;
  steps_fewer_ += threads() < configured_;
  if (!probing_) {
    since_probe_ += seconds;
    if (since_probe_ >= next_probe_) StartProbe();
    return;
  }
  const int at = window_ == 0 || window_ == 3 ? 0 : 1;
  if (!rebuilt) {
    sum_[at] += seconds;
    ++count_[at];
  }
  ++steps_in_window_;
  window_elapsed_ += seconds;
  // A neighbour far slower: no need to see more of it.
  if (window_ == 1 && window_elapsed_ > config_.give_up_above * first_elapsed_) {
    EndProbe(true);
    return;
  }
  // The first window sets the length of the others in steps.
  const bool done =
      window_ == 0 ? window_elapsed_ >= config_.window : steps_in_window_ >= window_steps_;
  if (!done) return;
  if (window_ == 0) {
    window_steps_ = steps_in_window_;
    first_elapsed_ = window_elapsed_;
  }
  // A neighbour far faster (the current count waits on a descheduled thread): take it now.
  if (window_ == 1 && count_[0] > 0 && count_[1] > 0 &&
      config_.give_up_above * sum_[1] * static_cast<double>(count_[0]) <
          sum_[0] * static_cast<double>(count_[1])) {
    EndProbe(false);
    return;
  }
  steps_in_window_ = 0;
  window_elapsed_ = 0;
  if (++window_ == 4) EndProbe(false);
}

}  // namespace dem

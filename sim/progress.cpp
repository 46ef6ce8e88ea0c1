// Progress lines on stderr. On a terminal one line is rewritten in place (\r, at most 4 times a
// second); otherwise (a log file, a pipe, CI) a plain line is appended every log_period seconds.
#include "sim/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

namespace sim {
namespace {

constexpr double kTtyPeriod = 0.25;  // seconds between rewrites of the live line

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

// "1:02:03" or "2:03" for a duration in seconds; "--:--" when unknown.
std::string Clock(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long long s = std::llround(seconds);
  char buffer[32];
  if (s >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%lld:%02lld:%02lld", s / 3600, (s / 60) % 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%lld:%02lld", s / 60, s % 60);
  }
  return buffer;
}

// "label  42.0%  t 0.021/0.05 s  elapsed 0:12  ETA 0:17  3.21 M particle-steps/s"
std::string Line(const std::string& label, double total_time, double sim_time,
                 int64_t particle_steps, double elapsed, bool done) {
  const double fraction =
      total_time > 0 ? std::min(1.0, std::max(0.0, sim_time / total_time)) : (done ? 1.0 : 0.0);
  const double eta =
      done ? 0.0 : (fraction > 0 ? elapsed * (1.0 - fraction) / fraction : std::nan(""));
  const double rate = elapsed > 0 ? static_cast<double>(particle_steps) / elapsed / 1e6 : 0.0;
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "%s %5.1f%%  t %.4g/%.4g s  elapsed %s  ETA %s  %.3g M particle-steps/s",
                label.c_str(), 100.0 * fraction, sim_time, total_time, Clock(elapsed).c_str(),
                Clock(eta).c_str(), rate);
  return buffer;
}

}  // namespace

Progress::Progress(std::string label, double total_time, bool quiet, double log_period)
    : label_(std::move(label)),
      total_time_(total_time),
      quiet_(quiet),
      tty_(isatty(STDERR_FILENO) == 1),
      log_period_(log_period),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

void Progress::Update(double sim_time, int64_t particle_steps) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (Seconds(now - last_print_) < (tty_ ? kTtyPeriod : log_period_)) return;
  last_print_ = now;
  const std::string line =
      Line(label_, total_time_, sim_time, particle_steps, Seconds(now - start_), false);
  if (tty_) {
    std::fprintf(stderr, "\r%s\x1b[K", line.c_str());  // ESC[K clears the rest of the old line
  } else {
    std::fprintf(stderr, "%s\n", line.c_str());
  }
  std::fflush(stderr);
}

void Progress::Finish(double sim_time, int64_t particle_steps) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  last_print_ = now;
  const std::string line =
      Line(label_, total_time_, sim_time, particle_steps, Seconds(now - start_), true);
  std::fprintf(stderr, tty_ ? "\r%s\x1b[K\n" : "%s\n", line.c_str());
  std::fflush(stderr);
}

namespace {

struct NamedPhase {
  const char* name;
  double seconds;
};

std::vector<NamedPhase> Named(const dem::PhaseTimes& p, double wall) {
  return {{"pairs", p.pairs},   {"integrate", p.integrate}, {"rebuild", p.rebuild},
          {"near", p.near},     {"mesh", p.mesh},           {"sleep", p.sleep},
          {"other", std::max(0.0, wall - p.Total())}};
}

}  // namespace

dem::PhaseTimes PhasesSince(const dem::PhaseTimes& now, const dem::PhaseTimes& before) {
  dem::PhaseTimes d;
  d.integrate = now.integrate - before.integrate;
  d.rebuild = now.rebuild - before.rebuild;
  d.near = now.near - before.near;
  d.pairs = now.pairs - before.pairs;
  d.mesh = now.mesh - before.mesh;
  d.sleep = now.sleep - before.sleep;
  return d;
}

std::string PhaseBreakdown(const dem::PhaseTimes& phases, double wall) {
  std::string line;
  for (const NamedPhase& p : Named(phases, wall)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s%s %.1f s (%.1f%%)", line.empty() ? "" : ", ", p.name,
                  p.seconds, 100.0 * p.seconds / std::max(wall, 1e-12));
    line += buf;
  }
  return line;
}

std::string PhaseJson(const dem::PhaseTimes& phases, double wall, double steps) {
  std::string json;
  for (const NamedPhase& p : Named(phases, wall)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s\"ms_%s\":%.4f", json.empty() ? "" : ",", p.name,
                  1e3 * p.seconds / std::max(steps, 1.0));
    json += buf;
  }
  return json;
}

}  // namespace sim

// Progress lines on stderr. On a terminal one line is rewritten in place (\r, at most 4 times a
// second); otherwise (a log file, a pipe, CI) a plain line is appended every log_period seconds.
#include "sim/loop/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <utility>
#include <vector>

namespace sim {
namespace {

constexpr double kTtyPeriod = 0.25;       // seconds between rewrites of the live line
constexpr double kFirstLine = 0.5;        // seconds before the first plain (not a terminal) line
constexpr double kSamplePeriod = 0.1;     // seconds between the samples of the recent rate
constexpr double kMinWindow = 2.0;        // the recent past is at least this long [s]
constexpr double kWindowFraction = 0.25;  // and at least this share of the elapsed time
constexpr double kMaxClock = 1e7;         // a clock reads "--:--" from here (116 days) [s]

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

}  // namespace

std::string Clock(double seconds) {
  if (!(seconds >= 0 && seconds < kMaxClock)) return "--:--";
  const long long s = std::llround(seconds);
  char buffer[32];
  if (s >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%lld:%02lld:%02lld", s / 3600, (s / 60) % 60, s % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%lld:%02lld", s / 60, s % 60);
  }
  return buffer;
}

namespace {

// "label  42.0%  t 0.021/0.05 s  elapsed 0:12  ETA 0:17  3.21 M particle-steps/s"
// (`particle_steps`: those of this sitting, done in `elapsed`).
std::string Line(const std::string& label, double fraction, double total_time, double sim_time,
                 int64_t particle_steps, double elapsed, double eta, bool upper_bound = false) {
  const double rate = elapsed > 0 ? static_cast<double>(particle_steps) / elapsed / 1e6 : 0.0;
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "%s %5.1f%%  t %.4g/%.4g s  elapsed %s  ETA %s%s  %.3g M particle-steps/s",
                label.c_str(), 100.0 * fraction, sim_time, total_time, Clock(elapsed).c_str(),
                upper_bound && std::isfinite(eta) ? "<= " : "", Clock(eta).c_str(), rate);
  return buffer;
}

bool g_live_line = false;  // a live progress line is on the terminal, not ended by a newline

}  // namespace

void Status(const char* format, ...) {
  if (g_live_line) {
    std::fputs("\r\x1b[K", stderr);  // clear it; the next update redraws it
    g_live_line = false;
  }
  va_list args;
  va_start(args, format);
  std::vfprintf(stderr, format, args);
  va_end(args);
  std::fflush(stderr);
}

Progress::Progress(std::string label, double total_time, bool quiet, double log_period,
                   std::function<double()> wall_clock)
    : label_(std::move(label)),
      total_time_(total_time),
      quiet_(quiet),
      tty_(isatty(STDERR_FILENO) == 1),
      log_period_(log_period),
      eta_(std::nan("")),
      wall_clock_(
          wall_clock ? std::move(wall_clock)
                     : [] { return Seconds(std::chrono::steady_clock::now().time_since_epoch()); }),
      start_(wall_clock_()),
      last_print_(start_) {}

void Progress::Begin(double sim_time, int64_t particle_steps) {
  sim0_ = sim_time;
  steps0_ = particle_steps;
  samples_.clear();
}

void Progress::Update(double sim_time, int64_t particle_steps) {
  if (quiet_) return;
  const double now = wall_clock_();
  const double elapsed = now - start_;
  if (samples_.empty() || elapsed - samples_.back().elapsed >= kSamplePeriod)
    samples_.push_back({elapsed, sim_time});
  // The first plain line comes after about a second, so that a log shows the run has started.
  const double period = tty_ ? kTtyPeriod : (printed_ ? log_period_ : kFirstLine);
  if (now - last_print_ < period) return;
  last_print_ = now;
  printed_ = true;
  // ETA: the simulated time left at the rate of the recent past.
  const double left = std::max(0.0, total_time_ - sim_time);
  const double window = std::max(kMinWindow, kWindowFraction * elapsed);
  auto first = std::upper_bound(samples_.begin(), samples_.end(), elapsed - window,
                                [](double e, const Sample& s) { return e < s.elapsed; });
  if (first != samples_.begin()) --first;
  const double d_sim = sim_time - first->sim_time, d_wall = elapsed - first->elapsed;
  // The mean of two estimates: at the recent rate (it follows a change of cost, late) and at the
  // whole run's rate (steady, but blind to a change). On scenes/sleep_check.yaml's dig, whose cost
  // per simulated second varies 1.5x, the mean errs least (bench/eta_check.sh).
  const double recent = d_sim > 0 && d_wall > 0 ? left * d_wall / d_sim : std::nan("");
  const double done = sim_time - sim0_;  // by this sitting
  const double overall = done > 0 ? left * elapsed / done : std::nan("");
  eta_ = std::isfinite(recent) ? 0.5 * (recent + overall) : overall;
  const double fraction =
      total_time_ > 0 ? std::min(1.0, std::max(0.0, sim_time / total_time_)) : 0.0;
  const std::string line =
      Line(label_, fraction, clock_start_ + total_time_, clock_start_ + sim_time,
           particle_steps - steps0_, elapsed, eta_, open_ended_);
  if (tty_) {
    std::fprintf(stderr, "\r%s\x1b[K", line.c_str());  // ESC[K clears the rest of the old line
    g_live_line = true;
  } else {
    std::fprintf(stderr, "%s\n", line.c_str());
  }
  std::fflush(stderr);
}

void Progress::Finish(double sim_time, int64_t particle_steps, bool done) {
  if (quiet_) return;
  const double now = wall_clock_();
  last_print_ = now;
  const double fraction = done              ? 1.0
                          : total_time_ > 0 ? std::min(1.0, std::max(0.0, sim_time / total_time_))
                                            : 0.0;
  const std::string line =
      Line(label_, fraction, clock_start_ + total_time_, clock_start_ + sim_time,
           particle_steps - steps0_, now - start_, done ? 0.0 : std::nan(""));
  std::fprintf(stderr, tty_ ? "\r%s\x1b[K\n" : "%s\n", line.c_str());
  g_live_line = false;
  std::fflush(stderr);
}

namespace {

struct NamedPhase {
  const char* name;
  double seconds;
};

std::vector<NamedPhase> Named(const dem::PhaseTimes& p, double wall) {
  return {{"pairs", p.pairs},     {"integrate", p.integrate},
          {"rebuild", p.rebuild}, {"near", p.near},
          {"mesh", p.mesh},       {"sleep", p.sleep},
          {"bonds", p.bonds},     {"other", std::max(0.0, wall - p.Total())}};
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
  d.bonds = now.bonds - before.bonds;
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

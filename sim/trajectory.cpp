#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// A segment may start this much before the previous one ends: amount / speed rounds (0.028 m at
// 0.14 m/s ends at 2.0000000000000004 s).
constexpr double kOverlapSlack = 1e-9;  // [s]

using Segment = TrajectorySpec::Segment;

double EndOf(const Segment& s) { return s.start + s.amount / s.speed; }

// How far the segment has gone at time t [m or rad]: exactly `amount` once it has ended.
double Progress(const Segment& s, double t) {
  if (!s.enabled || t <= s.start) return 0;
  if (t >= EndOf(s)) return s.amount;
  return s.speed * (t - s.start);
}

// The segment's speed while it is active ([start, end)), else 0.
double Rate(const Segment& s, double t) {
  return s.enabled && t >= s.start && t < EndOf(s) ? s.speed : 0;
}

[[noreturn]] void Invalid(const std::string& field, const std::string& expected, double got) {
  std::ostringstream msg;
  msg << field << ": expected " << expected << ", got " << got;
  throw std::invalid_argument(msg.str());
}

void CheckFinite(const std::string& field, const dem::Vec3& v) {
  if (!dem::IsFinite(v)) {
    std::ostringstream msg;
    msg << field << ": expected finite coordinates, got (" << v.x << ", " << v.y << ", " << v.z
        << ")";
    throw std::invalid_argument(msg.str());
  }
}

}  // namespace

TrajectorySpec Table1Preset() {
  TrajectorySpec s;
  s.initial_pitch = 90 * kDeg;
  s.approach = {true, 1.8, 0.14, 0.028};  // until 2.0 s
  s.rotation1 = {true, 2.0, 90 * kDeg, 90 * kDeg};
  s.linear = {true, 3.0, 0.3, 0.3};
  s.rotation2 = {true, 4.0, 90 * kDeg, 90 * kDeg};
  return s;
}

TrajectorySpec Table4Preset() {
  TrajectorySpec s;
  s.initial_pitch = 90 * kDeg;
  s.approach = {true, 0.0, 0.14, 0.028};  // for 0.2 s
  // "Right after": each segment starts where the previous one ends, computed, so that rounding
  // never makes two overlap.
  s.rotation1 = {true, 0.2, 30 * kDeg, 90 * kDeg};
  s.linear = {true, EndOf(s.rotation1), 0.1, 0.3};
  s.rotation2 = {true, EndOf(s.linear), 30 * kDeg, 90 * kDeg};
  return s;
}

dem::Quat PitchOrientation(double theta) {
  const dem::Quat level{0, 1, 0, 0};  // rpy(pi, 0, 0): half-turn about x, written exactly
  return dem::AxisAngle({0, 1, 0}, theta) * level;
}

Trajectory::Trajectory(const TrajectorySpec& spec) : spec_(spec) {
  CheckFinite("pivot_offset", spec.pivot_offset);
  CheckFinite("pivot_start", spec.pivot_start);
  if (!std::isfinite(spec.initial_pitch)) {
    Invalid("initial_pitch", "a finite angle [rad]", spec.initial_pitch);
  }
  const std::pair<const char*, const Segment*> segments[] = {{"approach", &spec.approach},
                                                             {"rotation1", &spec.rotation1},
                                                             {"linear", &spec.linear},
                                                             {"rotation2", &spec.rotation2}};
  const char* previous = nullptr;
  double previous_end = 0;
  for (const auto& [name, seg] : segments) {
    if (!seg->enabled) continue;
    const std::string n = name;
    if (!(seg->start >= 0) || !std::isfinite(seg->start)) {
      Invalid(n + ".start", "a finite time >= 0 [s]", seg->start);
    }
    if (!(seg->speed > 0) || !std::isfinite(seg->speed)) {
      Invalid(n + ".speed", "a finite number > 0", seg->speed);
    }
    if (!(seg->amount >= 0) || !std::isfinite(seg->amount)) {
      Invalid(n + ".amount", "a finite number >= 0", seg->amount);
    }
    if (previous != nullptr && seg->start < previous_end - kOverlapSlack) {
      std::ostringstream msg;
      msg << n << ".start: expected a time >= " << previous_end << " s (the end of " << previous
          << "; segments run in the order approach, rotation1, linear, rotation2 without "
             "overlapping), got "
          << seg->start;
      throw std::invalid_argument(msg.str());
    }
    previous = name;
    previous_end = EndOf(*seg);
    end_time_ = std::max(end_time_, previous_end);
  }
}

ScoopKinematics Trajectory::At(double t) const {
  const TrajectorySpec& s = spec_;
  ScoopKinematics k;
  // Pivot: down by the approach, forward by the linear push; pitch: down by both rotations.
  k.pivot = s.pivot_start + dem::Vec3{Progress(s.linear, t), 0, -Progress(s.approach, t)};
  k.pitch = s.initial_pitch - Progress(s.rotation1, t) - Progress(s.rotation2, t);
  k.pose.orientation = PitchOrientation(k.pitch);
  k.pose.position = k.pivot - dem::Rotate(k.pose.orientation, s.pivot_offset);

  // Twist: d(pitch)/dt about world +y; the origin moves with the pivot plus w x (origin - pivot).
  const dem::Vec3 pivot_velocity{Rate(s.linear, t), 0, -Rate(s.approach, t)};
  k.angular_velocity = {0, -(Rate(s.rotation1, t) + Rate(s.rotation2, t)), 0};
  k.velocity = pivot_velocity + dem::Cross(k.angular_velocity, k.pose.position - k.pivot);
  return k;
}

}  // namespace sim

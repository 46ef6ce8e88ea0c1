#include "sim/input/trajectory.h"

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
// A move may start this much before the previous one ends: amount / speed rounds (0.028 m at
// 0.14 m/s ends at 2.0000000000000004 s).
constexpr double kOverlapSlack = 1e-9;  // [s]

double EndOf(const Move& m) { return m.start + m.amount / m.speed; }

// How far the move has gone at time t [m, rad or s]: exactly `amount` once it has ended.
double Progress(const Move& m, double t) {
  if (t <= m.start) return 0;
  if (t >= EndOf(m)) return m.amount;
  return m.speed * (t - m.start);
}

bool Active(const Move& m, double t) { return t >= m.start && t < EndOf(m); }

std::string Str(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string Str(const dem::Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

// `move` < 0: a field of the spec itself.
[[noreturn]] void Invalid(int move, const std::string& name, const std::string& field,
                          const std::string& expected, double got) {
  throw TrajectoryError(move, name, field, expected, Str(got));
}

void CheckFinite(int move, const std::string& name, const std::string& field, const dem::Vec3& v) {
  if (!dem::IsFinite(v)) throw TrajectoryError(move, name, field, "finite coordinates", Str(v));
}

bool Same(const dem::Vec3& a, const dem::Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

}  // namespace

TrajectoryError::TrajectoryError(int move, const std::string& move_name, std::string field,
                                 std::string expected, std::string got)
    : std::invalid_argument((move >= 0 ? move_name + "." : std::string()) + field + ": expected " +
                            expected + ", got " + got),
      move_(move),
      field_(std::move(field)),
      expected_(std::move(expected)),
      got_(std::move(got)) {}

Move Translate(std::string name, const dem::Vec3& direction, double speed, double distance,
               double start) {
  Move m;
  m.kind = Move::Kind::kTranslate;
  m.name = std::move(name);
  m.axis = direction;
  m.speed = speed;
  m.amount = distance;
  m.start = start;
  return m;
}

Move Rotate(std::string name, const dem::Vec3& axis, double rate, double angle, double start) {
  Move m = Translate(std::move(name), axis, rate, angle, start);
  m.kind = Move::Kind::kRotate;
  return m;
}

Move RotateAbout(std::string name, const dem::Vec3& axis, double rate, double angle,
                 const dem::Vec3& point, double start) {
  Move m = Rotate(std::move(name), axis, rate, angle, start);
  m.about_pivot = false;
  m.point = point;
  return m;
}

Move Hold(std::string name, double duration, double start) {
  Move m;
  m.kind = Move::Kind::kHold;
  m.name = std::move(name);
  m.speed = 1;
  m.amount = duration;
  m.start = start;
  return m;
}

// The study's pitch rotations turn about world -y (theta decreases: the blade comes up).
constexpr dem::Vec3 kPitchDown{0, -1, 0};

TrajectorySpec Table1Preset() {
  TrajectorySpec s;
  s.initial_pitch = 90 * kDeg;
  s.moves = {Translate("approach", {0, 0, -1}, 0.14, 0.028, 1.8),  // until 2.0 s
             Rotate("rotation1", kPitchDown, 90 * kDeg, 90 * kDeg, 2.0),
             Translate("linear", {1, 0, 0}, 0.3, 0.3, 3.0),
             Rotate("rotation2", kPitchDown, 90 * kDeg, 90 * kDeg, 4.0)};
  return s;
}

TrajectorySpec Table4Preset() {
  TrajectorySpec s;
  s.initial_pitch = 90 * kDeg;
  // "Right after": each move starts where the previous one ends, computed, so that rounding never
  // makes two overlap.
  s.moves = {Translate("approach", {0, 0, -1}, 0.14, 0.028, 0.0),  // for 0.2 s
             Rotate("rotation1", kPitchDown, 30 * kDeg, 90 * kDeg, 0.2)};
  s.moves.push_back(Translate("linear", {1, 0, 0}, 0.1, 0.3, EndOf(s.moves[1])));
  s.moves.push_back(Rotate("rotation2", kPitchDown, 30 * kDeg, 90 * kDeg, EndOf(s.moves[2])));
  return s;
}

dem::Quat PitchOrientation(double theta) {
  const dem::Quat level{0, 1, 0, 0};  // rpy(pi, 0, 0): half-turn about x, written exactly
  return dem::AxisAngle({0, 1, 0}, theta) * level;
}

Trajectory::Trajectory(const TrajectorySpec& spec) : spec_(spec) {
  CheckFinite(-1, "", "pivot_offset", spec.pivot_offset);
  CheckFinite(-1, "", "pivot_start", spec.pivot_start);
  if (!std::isfinite(spec.initial_pitch)) {
    Invalid(-1, "", "initial_pitch", "a finite angle [rad]", spec.initial_pitch);
  }
  const Move* previous = nullptr;
  for (size_t i = 0; i < spec_.moves.size(); ++i) {
    Move& m = spec_.moves[i];
    const int index = static_cast<int>(i);
    if (m.name.empty()) m.name = "moves[" + std::to_string(i) + "]";
    const std::string& n = m.name;
    const bool hold = m.kind == Move::Kind::kHold;
    const bool after_previous = m.start == Move::kAfterPrevious;
    if (!after_previous && !(m.start >= 0 && std::isfinite(m.start))) {
      Invalid(index, n, "start", "a finite time >= 0 [s]", m.start);
    }
    if (!(m.speed > 0) || !std::isfinite(m.speed)) {
      Invalid(index, n, m.kind == Move::Kind::kRotate ? "rate" : "speed", "a finite number > 0",
              m.speed);
    }
    if (!(m.amount >= 0) || !std::isfinite(m.amount)) {
      Invalid(index, n,
              hold                            ? "duration"
              : m.kind == Move::Kind::kRotate ? "angle"
                                              : "distance",
              "a finite number >= 0", m.amount);
    }
    if (!hold) {
      const char* what = m.kind == Move::Kind::kRotate ? "axis" : "direction";
      CheckFinite(index, n, what, m.axis);
      const double length = dem::Norm(m.axis);
      if (!(length > 0)) Invalid(index, n, what, "a vector of non-zero length", length);
      if (length != 1) m.axis = (1 / length) * m.axis;
      if (m.about_pivot) m.point = spec_.pivot_offset;
      CheckFinite(index, n, "point", m.point);
    }
    const double previous_end = previous ? EndOf(*previous) : 0.0;
    if (after_previous) {
      m.start = previous_end;
    } else if (previous != nullptr && m.start < previous_end - kOverlapSlack) {
      throw TrajectoryError(index, n, "start",
                            "a time >= " + Str(previous_end) + " s (the end of " + previous->name +
                                "; moves run in order without overlapping)",
                            Str(m.start));
    }
    if (previous == nullptr) start_time_ = m.start;
    previous = &m;
    end_time_ = std::max(end_time_, EndOf(m));
  }
}

double Trajectory::LeadingDrop() const {
  double drop = 0;
  for (const Move& m : spec_.moves) {
    if (m.kind == Move::Kind::kRotate) break;
    if (m.kind == Move::Kind::kTranslate) drop += m.axis.z * m.amount;
  }
  return drop;
}

ScoopKinematics Trajectory::At(double t) const {
  const TrajectorySpec& s = spec_;
  // The pose as: pivot (a point of l_scoop) at `pivot` in world, orientation
  // AxisAngle(axis, angle) * base. Rotations about the current axis (or its opposite) add to
  // `angle`, so that a path of pitch rotations evaluates theta = initial - p1 - p2 exactly.
  dem::Vec3 pivot = s.pivot_start, point = s.pivot_offset;
  dem::Vec3 axis{0, 1, 0};
  double angle = s.initial_pitch;
  dem::Quat base{0, 1, 0, 0};  // the level orientation R0
  bool pitch_only = true;
  dem::Vec3 pivot_velocity, angular_velocity;
  for (const Move& m : s.moves) {
    if (m.kind == Move::Kind::kHold || t < m.start) continue;
    const double u = Progress(m, t);
    const bool active = Active(m, t);
    if (m.kind == Move::Kind::kTranslate) {
      pivot = pivot + m.axis * u;
      if (active) pivot_velocity += m.axis * m.speed;
      continue;
    }
    if (!Same(m.point, point)) {
      // The rotation's point becomes the pivot: where it is now in world.
      const dem::Quat q = dem::AxisAngle(axis, angle) * base;
      pivot = pivot + dem::Rotate(q, m.point - point);
      point = m.point;
    }
    if (Same(m.axis, axis)) {
      angle = angle + u;
    } else if (Same(-1.0 * m.axis, axis)) {
      angle = angle - u;
    } else {
      base = dem::AxisAngle(axis, angle) * base;
      axis = m.axis;
      angle = u;
      pitch_only = false;
    }
    if (active) angular_velocity += m.axis * m.speed;
  }
  ScoopKinematics k;
  k.pivot = pivot;
  k.pitch = pitch_only ? angle : std::nan("");
  k.pose.orientation = dem::AxisAngle(axis, angle) * base;
  k.pose.position = k.pivot - dem::Rotate(k.pose.orientation, point);
  // Twist: the origin moves with the pivot plus w x (origin - pivot).
  k.angular_velocity = angular_velocity;
  k.velocity = pivot_velocity + dem::Cross(k.angular_velocity, k.pose.position - k.pivot);
  return k;
}

}  // namespace sim

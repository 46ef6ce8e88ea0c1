#include "sim/trajectory.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Level orientation R0 = rpy(pi, 0, 0): l_scoop +x -> world +x, +y -> -y, +z -> -z.
const dem::Quat kLevel{0.0, 1.0, 0.0, 0.0};

std::string Seconds(double t) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g s", t);
  return buffer;
}

double SegmentEnd(const TrajectorySpec::Segment& s) { return s.start + s.amount / s.speed; }

// Progress of a segment at time t: the amount done so far, in [0, amount], and whether the
// segment is running (its rate applies).
double Done(const TrajectorySpec::Segment& s, double t, bool* running) {
  *running = false;
  if (!s.enabled || t <= s.start) return 0.0;
  const double end = SegmentEnd(s);
  if (t >= end) return s.amount;
  *running = true;
  return s.speed * (t - s.start);
}

}  // namespace

TrajectorySpec Table1Preset() {
  TrajectorySpec t;
  t.initial_pitch = 90 * kDeg;
  t.approach = {true, 1.8, 0.14, 0.14 * 0.2};
  t.rotation1 = {true, 2.0, 90 * kDeg, 90 * kDeg};
  t.linear = {true, 3.0, 0.3, 0.3};
  t.rotation2 = {true, 4.0, 90 * kDeg, 90 * kDeg};
  return t;
}

TrajectorySpec Table4Preset() {
  TrajectorySpec t;
  t.initial_pitch = 90 * kDeg;
  t.approach = {true, 0.0, 0.14, 0.14 * 0.2};
  t.rotation1 = {true, 0.2, 30 * kDeg, 90 * kDeg};
  t.linear = {true, 3.2, 0.1, 0.3};
  t.rotation2 = {true, 6.2, 30 * kDeg, 90 * kDeg};
  return t;
}

Trajectory::Trajectory(const TrajectorySpec& spec) : spec_(spec) {
  const char* names[4] = {"approach", "rotation1", "linear", "rotation2"};
  const TrajectorySpec::Segment* segs[4] = {&spec.approach, &spec.rotation1, &spec.linear,
                                            &spec.rotation2};
  double previous_end = -1e300;
  const char* previous = nullptr;
  for (int i = 0; i < 4; ++i) {
    const TrajectorySpec::Segment& s = *segs[i];
    if (!s.enabled) continue;
    if (!(s.speed > 0) || !(s.amount > 0) || !(s.start >= 0) || !std::isfinite(s.start))
      throw std::invalid_argument(std::string(names[i]) +
                                  ": needs start >= 0, speed > 0 and amount > 0");
    if (s.start < previous_end - 1e-12)
      throw std::invalid_argument(std::string(names[i]) + " starts at " + Seconds(s.start) +
                                  ", before " + previous + " ends at " + Seconds(previous_end));
    previous_end = SegmentEnd(s);
    previous = names[i];
  }
}

double Trajectory::end_time() const {
  double end = 0;
  for (const TrajectorySpec::Segment* s :
       {&spec_.approach, &spec_.rotation1, &spec_.linear, &spec_.rotation2})
    if (s->enabled) end = std::max(end, SegmentEnd(*s));
  return end;
}

// Pose: the pivot (fixed in l_scoop at pivot_offset) moves down during the approach and along +x
// during the linear segment; the pitch theta decreases during the rotations, which turn the
// scoop about the world y axis through the pivot: R(theta) = R_y(theta) R0.
ScoopKinematics Trajectory::At(double t) const {
  ScoopKinematics k;
  bool down = false, rot1 = false, lin = false, rot2 = false;
  const double dz = Done(spec_.approach, t, &down);
  const double a1 = Done(spec_.rotation1, t, &rot1);
  const double dx = Done(spec_.linear, t, &lin);
  const double a2 = Done(spec_.rotation2, t, &rot2);
  k.pitch = spec_.initial_pitch - a1 - a2;
  k.pivot = spec_.pivot_start + dem::Vec3{dx, 0.0, -dz};
  k.pose.orientation = dem::AxisAngle({0, 1, 0}, k.pitch) * kLevel;
  k.pose.position = k.pivot - dem::Rotate(k.pose.orientation, spec_.pivot_offset);
  // Twist of the active segment (segments do not overlap).
  dem::Vec3 v_pivot;
  if (down) v_pivot.z = -spec_.approach.speed;
  if (lin) v_pivot.x = spec_.linear.speed;
  double pitch_rate = 0;
  if (rot1) pitch_rate = -spec_.rotation1.speed;
  if (rot2) pitch_rate = -spec_.rotation2.speed;
  k.angular_velocity = {0.0, pitch_rate, 0.0};
  k.velocity = v_pivot + dem::Cross(k.angular_velocity, k.pose.position - k.pivot);
  return k;
}

}  // namespace sim

// The scoop's prescribed motion for a dig pass (paper Section 3, Tables 1 and 4): a vertical
// approach, a first rotation that brings the blade level, a linear push along the trench, a
// second rotation that lifts the blade out. Pure functions of time; the scene parser fills the
// spec from YAML.
//
// World frame: x along the trench (the digging direction), y lateral, z up (gravity -z).
// The pose is that of the l_scoop frame (assets/README.md) in world:
// x_world = position + Rotate(orientation, x_lscoop).
// Level orientation R0 = rpy(pi, 0, 0): l_scoop +x -> world +x (blade forward), +y -> world -y,
// +z -> world -z (the bottom normal points down). Pitch theta: R(theta) = R_y(theta) R0, with
// R_y a rotation about world +y, so the blade points along (cos theta, 0, -sin theta):
// theta = +pi/2 blade straight down, 0 level, -pi/2 blade up.
// The scoop turns about a world axis parallel to y through the pivot, a point fixed in l_scoop
// (pivot_offset; default the l_scoop origin, which lies on the j_scoop_yaw axis).
#pragma once

#include "dem/transform.h"
#include "dem/vec3.h"

namespace sim {

struct TrajectorySpec {             // every time in s, speed m/s, angle rad, rate rad/s
  dem::Vec3 pivot_offset{0, 0, 0};  // pivot in the l_scoop frame [m]
  dem::Vec3 pivot_start;            // world position of the pivot at t = 0 [m]
  double initial_pitch = 0;         // theta at t = 0 [rad]
  // One constant-speed move, active on [start, start + amount / speed]. A disabled segment is
  // skipped (its other fields are not read).
  struct Segment {
    bool enabled = false;
    double start = 0;   // [s]
    double speed = 0;   // [m/s] or [rad/s], > 0
    double amount = 0;  // [m] or [rad], >= 0
  };
  Segment approach;   // vertical: moves the pivot down (-z) by `amount`
  Segment rotation1;  // theta decreases by `amount` (the blade comes up toward level)
  Segment linear;     // the pivot moves +x by `amount`
  Segment rotation2;  // theta decreases by `amount` (the blade lifts out)
};

// Paper Table 1 (size and shape studies): approach 0.14 m/s from 1.8 s until 2.0 s (0.028 m);
// first rotation 90 deg/s from 2 s through 90 deg; linear 0.3 m/s from 3 s over 0.3 m; second
// rotation 90 deg/s from 4 s through 90 deg (ends 5.0 s). initial_pitch 90 deg (blade down),
// pivot at the l_scoop origin, pivot_start (0, 0, 0): the scene places it.
TrajectorySpec Table1Preset();

// Paper Table 4 (lookup table) gives speeds and amounts but no start times: approach 0.14 m/s
// from 0 s for 0.2 s (as in Table 1); first rotation 30 deg/s through 90 deg from 0.2 s; linear
// 0.1 m/s over 0.3 m right after (3.2 s); second rotation 30 deg/s through 90 deg right after
// (6.2 s), ending at 9.2 s. initial_pitch 90 deg, pivot and pivot_start as Table1Preset.
TrajectorySpec Table4Preset();

struct ScoopKinematics {
  dem::Pose pose;              // of the l_scoop frame in world
  dem::Vec3 velocity;          // of the l_scoop origin, world [m/s]
  dem::Vec3 angular_velocity;  // world [rad/s]
  double pitch = 0;            // theta [rad]
  dem::Vec3 pivot;             // pivot, world [m]
};

// The orientation of l_scoop at pitch theta: R_y(theta) R0 (see the top of this file).
dem::Quat PitchOrientation(double theta);

class Trajectory {
 public:
  // Validates the spec: finite values; for every enabled segment speed > 0, amount >= 0,
  // start >= 0; enabled segments in the order approach, rotation1, linear, rotation2, each
  // starting no earlier than the previous one ends (1e-9 s of slack for rounding in
  // amount / speed). Throws std::invalid_argument with a one-line message that starts with the
  // field ("linear.start: ..."); the scene parser turns it into an InputError.
  explicit Trajectory(const TrajectorySpec& spec);

  // Pose and twist at time t [s], piecewise analytic: the pose is continuous (constant before
  // the first segment, between segments and after the last); the twist is the active segment's
  // (segments are half-open, [start, end)), zero between segments. The velocity of the l_scoop
  // origin is v_pivot + w x (origin - pivot).
  ScoopKinematics At(double t) const;

  // End of the last enabled segment [s]; 0 when none is enabled.
  double end_time() const { return end_time_; }

  const TrajectorySpec& spec() const { return spec_; }

 private:
  TrajectorySpec spec_;
  double end_time_ = 0;
};

}  // namespace sim

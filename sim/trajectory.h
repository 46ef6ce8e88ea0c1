// The scoop's trajectory in a dig (paper section 3, Tables 1 and 4): a vertical approach, a
// rotation, a linear translation and a second rotation, each optional, as exact piecewise
// functions of time.
//
// World frame: x along the trench (digging direction), y lateral, z up. The pose is the l_scoop
// frame's: x_world = position + Rotate(orientation, x_lscoop). Level orientation
// R0 = rpy(pi, 0, 0) (blade forward, scoop bottom down); pitch theta: R(theta) = R_y(theta) R0,
// so theta = +90 deg points the blade straight down, 0 is level, -90 deg points it up. The
// rotations turn the scoop about the world y axis through the pivot, a point fixed in l_scoop.
#pragma once

#include "dem/transform.h"
#include "dem/vec3.h"

namespace sim {

struct TrajectorySpec {
  dem::Vec3 pivot_offset{0, 0, 0};  // pivot in the l_scoop frame [m]
  dem::Vec3 pivot_start;            // world position of the pivot at t = 0 [m]
  double initial_pitch = 0;         // theta at t = 0 [rad]
  // A segment runs on [start, start + amount / speed]; speed in m/s or rad/s, amount in m or rad.
  struct Segment {
    bool enabled = false;
    double start = 0;
    double speed = 0;
    double amount = 0;
  };
  Segment approach;   // vertical: the pivot moves down (-z) by `amount`
  Segment rotation1;  // theta decreases by `amount`
  Segment linear;     // the pivot moves along +x by `amount`
  Segment rotation2;  // theta decreases by `amount`
};

// Paper Table 1 (size and shape studies): approach 0.14 m/s from 1.8 s to 2.0 s; rotation
// 90 deg/s from 2 s through 90 deg; linear 0.3 m/s from 3 s over 0.3 m; rotation 90 deg/s from
// 4 s through 90 deg; initial pitch 90 deg.
TrajectorySpec Table1Preset();
// Paper Table 4 (lookup-table set) gives rates and amounts but no start times: approach 0.14 m/s
// for 0.2 s from 0 s (as Table 1), rotation 30 deg/s through 90 deg from 0.2 s, linear 0.1 m/s
// over 0.3 m from 3.2 s, rotation 30 deg/s through 90 deg from 6.2 s; ends at 9.2 s.
TrajectorySpec Table4Preset();

struct ScoopKinematics {
  dem::Pose pose;              // l_scoop in world
  dem::Vec3 velocity;          // of the l_scoop origin [m/s], world
  dem::Vec3 angular_velocity;  // [rad/s], world
  double pitch = 0;            // theta [rad]
  dem::Vec3 pivot;             // pivot in world [m]
};

class Trajectory {
 public:
  // Throws std::invalid_argument when an enabled segment has start < 0, speed <= 0 or
  // amount <= 0, or starts before the previous enabled one ends.
  explicit Trajectory(const TrajectorySpec& spec);
  // Exact pose at time t (continuous), with the twist of the segment running at t (zero between
  // segments).
  ScoopKinematics At(double t) const;
  double end_time() const;  // end of the last enabled segment [s]
  const TrajectorySpec& spec() const { return spec_; }

 private:
  TrajectorySpec spec_;
};

}  // namespace sim

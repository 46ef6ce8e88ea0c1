// The scoop's prescribed motion for a dig pass: a tool path written as a list of moves, as
// LIGGGHTS users chain `fix move/mesh` blocks. A move translates the scoop at a constant velocity,
// rotates it at a constant rate about a world axis through a point fixed in the scoop, or holds
// it. The study's trajectories (paper Section 3, Tables 1 and 4: a vertical approach, a first
// rotation that brings the blade level, a linear push along the trench, a second rotation that
// lifts the blade out) are two such lists (Table1Preset, Table4Preset). Pure functions of time;
// the scene parser fills the spec from YAML.
//
// World frame: x along the trench (the digging direction), y lateral, z up (gravity -z).
// The pose is that of the l_scoop frame (assets/README.md) in world:
// x_world = position + Rotate(orientation, x_lscoop).
// Level orientation R0 = rpy(pi, 0, 0): l_scoop +x -> world +x (blade forward), +y -> world -y,
// +z -> world -z (the bottom normal points down). Pitch theta: R(theta) = R_y(theta) R0, with
// R_y a rotation about world +y, so the blade points along (cos theta, 0, -sin theta):
// theta = +pi/2 blade straight down, 0 level, -pi/2 blade up. The path starts at pitch
// initial_pitch with the pivot (a point fixed in l_scoop, pivot_offset; default the l_scoop
// origin, which lies on the j_scoop_yaw axis) at pivot_start.
#pragma once

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "dem/transform.h"
#include "dem/vec3.h"

namespace sim {

// One constant-rate move of the tool path, active on [start, start + amount / speed).
struct Move {
  static constexpr double kAfterPrevious = -std::numeric_limits<double>::infinity();
  enum class Kind { kTranslate, kRotate, kHold };
  Kind kind = Kind::kHold;
  std::string name;               // for messages: "approach", "moves[2]", ...
  double start = kAfterPrevious;  // [s]; kAfterPrevious: when the previous one ends (first: 0)
  dem::Vec3 axis;           // translate: unit direction of travel; rotate: unit axis (right hand),
                            // both in world axes (before the dig's heading turns the whole path)
  double speed = 1;         // [m/s] or [rad/s], > 0 (hold: 1, so that amount is its duration)
  double amount = 0;        // [m], [rad] or (hold) [s], >= 0
  bool about_pivot = true;  // rotate: the axis passes through the path's pivot (pivot_offset)
  dem::Vec3 point;          // rotate, when not about_pivot: the point of l_scoop it passes
                            // through [m]
};

// The whole path. Move starts are resolved by Trajectory (explicit ones kept as written).
struct TrajectorySpec {
  dem::Vec3 pivot_offset{0, 0, 0};  // pivot in the l_scoop frame [m]
  dem::Vec3 pivot_start;            // world position of the pivot at t = 0 [m]
  double initial_pitch = 0;         // theta at t = 0 [rad]
  std::vector<Move> moves;          // in order; each starts no earlier than the previous ends
};

// Move builders: Rotate turns about the path's pivot, RotateAbout about a given point of l_scoop.
Move Translate(std::string name, const dem::Vec3& direction, double speed, double distance,
               double start = Move::kAfterPrevious);
Move Rotate(std::string name, const dem::Vec3& axis, double rate, double angle,
            double start = Move::kAfterPrevious);
Move RotateAbout(std::string name, const dem::Vec3& axis, double rate, double angle,
                 const dem::Vec3& point, double start = Move::kAfterPrevious);
Move Hold(std::string name, double duration, double start = Move::kAfterPrevious);

// Paper Table 1 (size and shape studies): approach 0.14 m/s from 1.8 s until 2.0 s (0.028 m);
// first rotation 90 deg/s from 2 s through 90 deg; linear 0.3 m/s from 3 s over 0.3 m; second
// rotation 90 deg/s from 4 s through 90 deg (ends 5.0 s). initial_pitch 90 deg (blade down),
// pivot at the l_scoop origin, pivot_start (0, 0, 0): the scene places it. The moves are named
// approach, rotation1, linear and rotation2 (the scene's keys of the same names override them).
TrajectorySpec Table1Preset();

// Paper Table 4 (lookup table) gives speeds and amounts but no start times: approach 0.14 m/s
// from 0 s for 0.2 s (as in Table 1); first rotation 30 deg/s through 90 deg from 0.2 s; linear
// 0.1 m/s over 0.3 m right after (3.2 s); second rotation 30 deg/s through 90 deg right after
// (6.2 s), ending at 9.2 s. initial_pitch 90 deg, pivot and pivot_start as Table1Preset.
TrajectorySpec Table4Preset();

// A TrajectorySpec that Trajectory refuses, as data: `move` is the index of the offending move in
// spec.moves, or -1 for a field of the spec itself; `field` is that field's own name ("start",
// "speed", "rate", "distance", "angle", "duration", "direction", "axis", "point"; or
// "pivot_offset", "pivot_start", "initial_pitch"); `expected` and `got` are in the spec's units
// (s, m, rad). The scene parser maps them to its YAML keys. what() is one line,
// "NAME.FIELD: expected EXPECTED, got GOT" (NAME the move's name; no "NAME." for the spec's own).
class TrajectoryError : public std::invalid_argument {
 public:
  TrajectoryError(int move, const std::string& move_name, std::string field, std::string expected,
                  std::string got);
  int move() const { return move_; }
  const std::string& field() const { return field_; }
  const std::string& expected() const { return expected_; }
  const std::string& got() const { return got_; }

 private:
  int move_ = -1;
  std::string field_, expected_, got_;
};

struct ScoopKinematics {
  dem::Pose pose;              // of the l_scoop frame in world
  dem::Vec3 velocity;          // of the l_scoop origin, world [m/s]
  dem::Vec3 angular_velocity;  // world [rad/s]
  double pitch = 0;            // theta [rad] while every rotation so far is about world +-y
  dem::Vec3 pivot;             // pivot (the point of the last rotation, else pivot_offset), world
};

// The orientation of l_scoop at pitch theta: R_y(theta) R0 (see the top of this file).
dem::Quat PitchOrientation(double theta);

class Trajectory {
 public:
  // Validates the spec and resolves the move starts: finite values; for every move speed > 0,
  // amount >= 0, an axis of non-zero length (normalised here), start >= 0 when given and no
  // earlier than the previous move ends (1e-9 s of slack for rounding in amount / speed). Throws
  // TrajectoryError (a std::invalid_argument) naming the move and its field; the scene parser
  // maps it onto the YAML key that wrote the value.
  explicit Trajectory(const TrajectorySpec& spec);

  // Pose and twist at time t [s], piecewise analytic: the pose is continuous (constant before
  // the first move, between moves and after the last); the twist is the active move's (moves are
  // half-open, [start, end)), zero between moves. Each move contributes its progress
  // min(speed (t - start), amount), applied in order: a translation moves the pivot, a rotation
  // turns the scoop about its point (which becomes the pivot). The velocity of the l_scoop origin
  // is v_pivot + w x (origin - pivot).
  ScoopKinematics At(double t) const;

  // Start of the first move and end of the last [s]; both 0 when there is none.
  double start_time() const { return start_time_; }
  double end_time() const { return end_time_; }

  // Vertical displacement of the pivot by the translations before the first rotation [m]: the
  // approach, which a dig's depth is measured after.
  double LeadingDrop() const;

  const TrajectorySpec& spec() const { return spec_; }

 private:
  TrajectorySpec spec_;  // starts resolved, axes normalised
  double start_time_ = 0;
  double end_time_ = 0;
};

}  // namespace sim

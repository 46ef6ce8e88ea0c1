// Scoop trajectory (sim/input/trajectory.cpp) against the paper's Tables 1 and 4, written out here
// independently: pitch = initial - rate (t - start) inside a rotation, the pivot moving at
// constant speed inside the approach and the linear push, the blade along (cos theta, 0, -sin
// theta).
#include "sim/input/trajectory.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 1e-12;  // [m] and [rad]

// Pitch and pivot (world) that the paper's event table gives at time t.
struct Expected {
  double pitch;
  dem::Vec3 pivot;
};

// A paper event table: approach 0.14 m/s for 0.2 s, rotation through 90 deg, linear push over
// 0.3 m, rotation through 90 deg, each starting at its own time.
struct EventTable {
  double approach, rotation1, linear, rotation2;  // start times [s]
  double rotation_rate;                           // [rad/s]
  double linear_speed;                            // [m/s]
};
// Table 1: approach on [1.8, 2.0), 90 deg/s on [2, 3), 0.3 m/s on [3, 4), 90 deg/s on [4, 5).
constexpr EventTable kTable1{1.8, 2.0, 3.0, 4.0, kPi / 2, 0.3};
// Table 4 (start times chosen as in Table4Preset): approach on [0, 0.2), 30 deg/s on [0.2, 3.2),
// 0.1 m/s on [3.2, 6.2), 30 deg/s on [6.2, 9.2).
constexpr EventTable kTable4{0.0, 0.2, 3.2, 6.2, kPi / 6, 0.1};

Expected TableAt(const EventTable& e, double t, const dem::Vec3& p0) {
  const double half_pi = kPi / 2;
  if (t < e.approach) return {half_pi, p0};
  if (t < e.rotation1) return {half_pi, p0 + dem::Vec3{0, 0, -0.14 * (t - e.approach)}};
  const dem::Vec3 down = p0 + dem::Vec3{0, 0, -0.028};
  if (t < e.linear) return {half_pi - e.rotation_rate * (t - e.rotation1), down};
  if (t < e.rotation2) return {0.0, down + dem::Vec3{e.linear_speed * (t - e.linear), 0, 0}};
  const dem::Vec3 ahead = down + dem::Vec3{0.3, 0, 0};
  if (t < e.rotation2 + half_pi / e.rotation_rate) {
    return {-e.rotation_rate * (t - e.rotation2), ahead};
  }
  return {-half_pi, ahead};
}

// l_scoop axes in world at pitch theta, from R = R_y(theta) diag(1, -1, -1) written out.
struct Axes {
  dem::Vec3 x, y, z;
};
Axes AxesAt(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  return {{c, 0, -s}, {0, -1, 0}, {-s, 0, -c}};
}

void ExpectVecNear(const dem::Vec3& got, const dem::Vec3& want, double tol,
                   const std::string& what) {
  EXPECT_NEAR(got.x, want.x, tol) << what;
  EXPECT_NEAR(got.y, want.y, tol) << what;
  EXPECT_NEAR(got.z, want.z, tol) << what;
}

// The pose at t equals the table's, for a pivot offset from the l_scoop origin.
void CheckPoses(const Trajectory& traj, const EventTable& table, const std::vector<double>& times) {
  const dem::Vec3 p0 = traj.spec().pivot_start, off = traj.spec().pivot_offset;
  for (double t : times) {
    const std::string at = "t = " + std::to_string(t);
    const Expected e = TableAt(table, t, p0);
    const ScoopKinematics k = traj.At(t);
    EXPECT_NEAR(k.pitch, e.pitch, kTol) << at;
    ExpectVecNear(k.pivot, e.pivot, kTol, at + " pivot");
    const Axes a = AxesAt(e.pitch);
    ExpectVecNear(dem::Rotate(k.pose.orientation, {1, 0, 0}), a.x, kTol, at + " blade (l_scoop x)");
    ExpectVecNear(dem::Rotate(k.pose.orientation, {0, 1, 0}), a.y, kTol, at + " l_scoop y");
    ExpectVecNear(dem::Rotate(k.pose.orientation, {0, 0, 1}), a.z, kTol, at + " l_scoop z");
    const dem::Vec3 origin = e.pivot - (off.x * a.x + off.y * a.y + off.z * a.z);
    ExpectVecNear(k.pose.position, origin, kTol, at + " l_scoop origin");
  }
}

// The twist equals a central difference of the pose (origin velocity; w = 1/2 sum e_i x de_i/dt
// over the frame's axes), relative 1e-6 of the larger of the two speeds.
void CheckTwist(const Trajectory& traj, const std::vector<double>& times) {
  const double h = 1e-6;
  for (double t : times) {
    const std::string at = "t = " + std::to_string(t);
    const ScoopKinematics k = traj.At(t), before = traj.At(t - h), after = traj.At(t + h);
    const dem::Vec3 v_fd = (1 / (2 * h)) * (after.pose.position - before.pose.position);
    dem::Vec3 w_fd;
    for (const dem::Vec3& e : {dem::Vec3{1, 0, 0}, dem::Vec3{0, 1, 0}, dem::Vec3{0, 0, 1}}) {
      const dem::Vec3 ei = dem::Rotate(k.pose.orientation, e);
      const dem::Vec3 dei = (1 / (2 * h)) * (dem::Rotate(after.pose.orientation, e) -
                                             dem::Rotate(before.pose.orientation, e));
      w_fd += 0.5 * dem::Cross(ei, dei);
    }
    const double v_scale = std::max(dem::Norm(k.velocity), 1e-3);
    const double w_scale = std::max(dem::Norm(k.angular_velocity), 1e-3);
    ExpectVecNear(k.velocity, v_fd, 1e-6 * v_scale, at + " velocity");
    ExpectVecNear(k.angular_velocity, w_fd, 1e-6 * w_scale, at + " angular velocity");
  }
}

// The preset's move of that name.
Move& Named(TrajectorySpec& spec, const std::string& name) {
  for (Move& m : spec.moves)
    if (m.name == name) return m;
  throw std::logic_error("no move " + name);
}

TrajectorySpec WithPivot(TrajectorySpec s) {
  s.pivot_start = {0.12, -0.03, 0.25};
  s.pivot_offset = {0.01, 0.002, 0.05};
  return s;
}

TEST(TrajectoryTest, Table1PoseMatchesPaper) {
  for (const TrajectorySpec& spec : {Table1Preset(), WithPivot(Table1Preset())}) {
    CheckPoses(Trajectory(spec), kTable1,
               {-1.0, 0.0, 1.0, 1.8,   1.85, 1.9,  1.99, 2.0,  2.3, 2.5, 2.99,
                3.0,  3.3, 3.7, 3.999, 4.0,  4.25, 4.5,  4.99, 5.0, 5.5, 100.0});
  }
}

TEST(TrajectoryTest, Table4PoseMatchesPaper) {
  for (const TrajectorySpec& spec : {Table4Preset(), WithPivot(Table4Preset())}) {
    CheckPoses(Trajectory(spec), kTable4,
               {0.0, 0.05, 0.1, 0.19, 0.2, 1.0, 2.0, 3.19, 3.2, 4.0, 5.5, 6.19, 6.2, 7.0, 8.5, 9.19,
                9.2, 10.0});
  }
}

// Totals: 90 deg per rotation, 0.3 m of push, 0.028 m of approach; ends at 5.0 s and 9.2 s.
TEST(TrajectoryTest, SegmentEndsMatchTables) {
  const dem::Vec3 p0{0.12, -0.03, 0.25};
  struct Case {
    TrajectorySpec spec;
    double first_rotation_end, end;
  };
  for (const Case& c :
       {Case{WithPivot(Table1Preset()), 3.0, 5.0}, Case{WithPivot(Table4Preset()), 3.2, 9.2}}) {
    const TrajectorySpec& spec = c.spec;
    const Trajectory traj(spec);
    EXPECT_NEAR(traj.end_time(), c.end, kTol);
    const double mid = c.first_rotation_end;
    EXPECT_NEAR(traj.At(mid).pitch, 0.0, kTol);
    EXPECT_NEAR(spec.initial_pitch - traj.At(mid).pitch, kPi / 2, kTol);
    const ScoopKinematics end = traj.At(traj.end_time());
    EXPECT_NEAR(end.pitch, -kPi / 2, kTol);
    EXPECT_NEAR(end.pivot.x - p0.x, 0.3, kTol);
    EXPECT_NEAR(p0.z - end.pivot.z, 0.028, kTol);
    EXPECT_NEAR(end.pivot.y, p0.y, 0.0);
    // Blade straight up at the end, straight down at the start.
    ExpectVecNear(dem::Rotate(end.pose.orientation, {1, 0, 0}), {0, 0, 1}, kTol, "blade at end");
    ExpectVecNear(dem::Rotate(traj.At(0).pose.orientation, {1, 0, 0}), {0, 0, -1}, kTol,
                  "blade at start");
  }
}

TEST(TrajectoryTest, TwistMatchesFiniteDifferenceInsideSegments) {
  CheckTwist(Trajectory(WithPivot(Table1Preset())),
             {1.85, 1.95, 2.1, 2.5, 2.9, 3.1, 3.5, 3.9, 4.1, 4.5, 4.9});
  CheckTwist(Trajectory(WithPivot(Table4Preset())), {0.1, 0.5, 1.7, 3.0, 3.5, 6.0, 6.5, 8.0, 9.1});
  // Outside every segment the twist is zero.
  const Trajectory t1(WithPivot(Table1Preset()));
  for (double t : {0.0, 1.0, 1.79, 5.0, 6.0}) {
    EXPECT_EQ(dem::Norm(t1.At(t).velocity), 0.0) << t;
    EXPECT_EQ(dem::Norm(t1.At(t).angular_velocity), 0.0) << t;
  }
}

// A gap between segments: the pose holds, the twist is zero.
TEST(TrajectoryTest, PoseHoldsBetweenSegments) {
  TrajectorySpec spec = WithPivot(Table1Preset());
  Named(spec, "linear").start = 3.5;
  Named(spec, "rotation2").start = 4.5;
  const Trajectory traj(spec);
  const ScoopKinematics a = traj.At(3.0), b = traj.At(3.25), c = traj.At(3.5);
  for (const ScoopKinematics& k : {b, c}) {
    ExpectVecNear(k.pose.position, a.pose.position, kTol, "position");
    EXPECT_NEAR(k.pitch, a.pitch, kTol);
  }
  EXPECT_EQ(dem::Norm(b.velocity), 0.0);
  EXPECT_EQ(dem::Norm(b.angular_velocity), 0.0);
  EXPECT_NEAR(traj.end_time(), 5.5, kTol);
}

// Only the linear segment, at pitch 0 (the testbed's constant-speed push, FACTS section 5):
// level scoop, constant velocity, no rotation.
TEST(TrajectoryTest, LinearOnlyIsAConstantSpeedPush) {
  TrajectorySpec spec;
  spec.pivot_start = {0.05, 0, 0.02};
  spec.initial_pitch = 0;
  spec.moves = {Translate("linear", {1, 0, 0}, 0.01, 0.3, 0.5)};
  const Trajectory traj(spec);
  EXPECT_NEAR(traj.end_time(), 30.5, 1e-9);
  for (double t : {0.6, 5.0, 17.25, 30.4}) {
    const ScoopKinematics k = traj.At(t);
    ExpectVecNear(k.pose.position, {0.05 + 0.01 * (t - 0.5), 0, 0.02}, kTol, "position");
    ExpectVecNear(k.velocity, {0.01, 0, 0}, 0.0, "velocity");
    ExpectVecNear(k.angular_velocity, {0, 0, 0}, 0.0, "angular velocity");
    ExpectVecNear(dem::Rotate(k.pose.orientation, {0, 0, 1}), {0, 0, -1}, kTol, "bottom normal");
  }
  ExpectVecNear(traj.At(40).pose.position, {0.35, 0, 0.02}, kTol, "after the push");
}

// Bad specs throw std::invalid_argument, naming the field first.
TEST(TrajectoryTest, InvalidSpecsThrow) {
  auto message = [](const TrajectorySpec& spec) -> std::string {
    try {
      Trajectory traj(spec);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  TrajectorySpec s = Table1Preset();
  Named(s, "rotation1").speed = 0;
  EXPECT_EQ(message(s).rfind("rotation1.rate: ", 0), 0u) << message(s);
  Named(s, "rotation1").speed = -1;
  EXPECT_EQ(message(s).rfind("rotation1.rate: ", 0), 0u) << message(s);
  s = Table1Preset();
  Named(s, "linear").amount = -0.1;
  EXPECT_EQ(message(s).rfind("linear.distance: ", 0), 0u) << message(s);
  s = Table1Preset();
  Named(s, "linear").start = 2.5;  // overlaps rotation1 [2, 3)
  EXPECT_EQ(message(s).rfind("linear.start: ", 0), 0u) << message(s);
  s = Table1Preset();
  Named(s, "rotation1").start = 1.0;  // before the approach ends: out of order
  EXPECT_EQ(message(s).rfind("rotation1.start: ", 0), 0u) << message(s);
  s = Table1Preset();
  Named(s, "approach").start = -1;
  EXPECT_EQ(message(s).rfind("approach.start: ", 0), 0u) << message(s);
  s = Table1Preset();
  Named(s, "rotation2").axis = {0, 0, 0};
  EXPECT_EQ(message(s).rfind("rotation2.axis: ", 0), 0u) << message(s);
  s = Table1Preset();
  s.moves.push_back(Hold("pause", -0.5));
  EXPECT_EQ(message(s).rfind("pause.duration: ", 0), 0u) << message(s);
  s = Table1Preset();
  s.initial_pitch = NAN;
  EXPECT_EQ(message(s).rfind("initial_pitch: ", 0), 0u) << message(s);
  s = Table1Preset();
  s.pivot_start.z = INFINITY;
  EXPECT_EQ(message(s).rfind("pivot_start: ", 0), 0u) << message(s);
}

// A path the study's four segments cannot express: Table 1, then a vertical lift of 0.05 m at
// 0.1 m/s after the tilt, a 0.25 s hold, and a sideways sweep of 0.04 m at 0.2 m/s along +y.
// Written out independently: once rotation2 has ended (5.0 s) the orientation is the blade-up
// one, R = R_y(-pi/2) R0, and the pivot moves by +z 0.1 (t - 5) until 5.5 s, holds until
// 5.75 s, then by +y 0.2 (t - 5.75) until 5.95 s.
TEST(TrajectoryTest, LiftAndSweepAfterTheTiltMatchClosedForm) {
  TrajectorySpec spec = WithPivot(Table1Preset());
  spec.moves.push_back(Translate("lift", {0, 0, 1}, 0.1, 0.05));
  spec.moves.push_back(Hold("pause", 0.25));
  spec.moves.push_back(Translate("sweep", {0, 1, 0}, 0.2, 0.04));
  const Trajectory traj(spec);
  EXPECT_NEAR(traj.end_time(), 5.95, kTol);
  const dem::Vec3 p0 = spec.pivot_start, off = spec.pivot_offset;
  const dem::Vec3 after_tilt = p0 + dem::Vec3{0.3, 0, -0.028};
  const Axes a = AxesAt(-kPi / 2);
  for (double t : {5.0, 5.1, 5.25, 5.4999, 5.5, 5.6, 5.75, 5.8, 5.9, 5.95, 7.0}) {
    const std::string at = "t = " + std::to_string(t);
    dem::Vec3 pivot = after_tilt + dem::Vec3{0, 0, 0.1 * (std::min(t, 5.5) - 5.0)};
    if (t > 5.75) pivot.y += 0.2 * (std::min(t, 5.95) - 5.75);
    const ScoopKinematics k = traj.At(t);
    ExpectVecNear(k.pivot, pivot, kTol, at + " pivot");
    ExpectVecNear(dem::Rotate(k.pose.orientation, {1, 0, 0}), a.x, kTol, at + " blade");
    ExpectVecNear(dem::Rotate(k.pose.orientation, {0, 0, 1}), a.z, kTol, at + " l_scoop z");
    const dem::Vec3 origin = pivot - (off.x * a.x + off.y * a.y + off.z * a.z);
    ExpectVecNear(k.pose.position, origin, kTol, at + " origin");
    const dem::Vec3 v = t < 5.5 ? dem::Vec3{0, 0, 0.1}
                        : (t >= 5.75 && t < 5.95) ? dem::Vec3{0, 0.2, 0}
                                                  : dem::Vec3{0, 0, 0};
    ExpectVecNear(k.velocity, v, kTol, at + " velocity");
  }
  CheckTwist(traj, {5.2, 5.4, 5.8, 5.9});
}

// A rotation about a world axis that is not the pitch axis, through a point of the scoop other
// than the pivot: the point stays put and every other point turns about it, R = AxisAngle(z,
// rate (t - start)) R_before (Rodrigues, written out for a quarter turn).
TEST(TrajectoryTest, YawAboutAnotherPointKeepsThatPointFixed) {
  TrajectorySpec spec;
  spec.pivot_start = {0.1, 0.2, 0.3};
  spec.initial_pitch = 0;  // level: R0
  const dem::Vec3 tip{0.12, 0.0, 0.02};  // a point of l_scoop
  spec.moves = {RotateAbout("yaw", {0, 0, 2}, kPi / 2, kPi / 2, tip, 1.0)};  // axis normalised
  const Trajectory traj(spec);
  const dem::Vec3 tip_world{0.1 + 0.12, 0.2 - 0.0, 0.3 - 0.02};  // R0 = diag(1, -1, -1)
  for (double t : {0.5, 1.0, 1.25, 1.5, 2.0, 3.0}) {
    const std::string at = "t = " + std::to_string(t);
    const ScoopKinematics k = traj.At(t);
    ExpectVecNear(dem::Apply(k.pose, tip), tip_world, kTol, at + " tip");
    const double phi = kPi / 2 * (std::clamp(t, 1.0, 2.0) - 1.0);
    // l_scoop x (world +x when level) turned by phi about +z.
    ExpectVecNear(dem::Rotate(k.pose.orientation, {1, 0, 0}), {std::cos(phi), std::sin(phi), 0},
                  kTol, at + " blade");
  }
  CheckTwist(traj, {1.1, 1.5, 1.9});
}

}  // namespace
}  // namespace sim

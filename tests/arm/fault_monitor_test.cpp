// Tests of arm/fault_monitor.cpp: each rule of fault_monitor.h on made-up joint samples (no
// Bullet), and the reactions' data.
#include "arm/fault_monitor.h"

#include <gtest/gtest.h>

#include <cmath>

namespace arm {
namespace {

const ArmModel& Lander() {
  static const ArmModel model = LoadArmModel(ARM_TEST_URDF);
  return model;
}

ArmSample Quiet(double t) {
  ArmSample s;
  s.time = t;
  s.joints.assign(6, JointSample{});
  s.has_ft = true;
  return s;
}

// The lander's ArmFaultsStatus bit values (FACTS section 6).
TEST(FaultMonitorTest, BitValues) {
  EXPECT_EQ(kFaultHardware, 1u);
  EXPECT_EQ(kFaultTrajectoryGeneration, 2u);
  EXPECT_EQ(kFaultCollision, 4u);
  EXPECT_EQ(kFaultEStop, 8u);
  EXPECT_EQ(kFaultPositionLimit, 16u);
  EXPECT_EQ(kFaultJointTorqueLimit, 32u);
  EXPECT_EQ(kFaultVelocityLimit, 64u);
  EXPECT_EQ(kFaultNoForceData, 128u);
  EXPECT_EQ(kFaultForceTorqueLimit, 256u);
  EXPECT_STREQ(FaultName(kFaultJointTorqueLimit), "JOINT_TORQUE_LIMIT");
}

// A load ramp: the demanded torque on j_dist_pitch (effort 25.7 N m) grows as 100 t N m, sampled
// every 1 ms; it crosses the limit at the first sample t_c >= 0.257 s. With a 0.1 s hold,
// JOINT_TORQUE_LIMIT is raised at the first sample t >= t_c + 0.1 s (within one sample of it),
// never before, once.
TEST(FaultMonitorTest, TorqueRampRaisesAfterTheHoldTime) {
  FaultRules rules;
  rules.torque_hold_time = 0.1;
  FaultMonitor monitor(Lander(), rules);
  const double dt = 1e-3;
  double t_cross = -1;
  for (int k = 0; k <= 600; ++k) {
    ArmSample s = Quiet(k * dt);
    s.joints[3].demanded = 100 * s.time;
    s.joints[3].applied = std::min(s.joints[3].demanded, 25.7);
    if (t_cross < 0 && s.joints[3].demanded >= 25.7) t_cross = s.time;
    const FaultStep step = monitor.Update(s);
    if (t_cross < 0 || s.time < t_cross + 0.1 - 1e-9) {
      EXPECT_EQ(step.active & kFaultJointTorqueLimit, 0u) << "too early at t = " << s.time;
    }
  }
  ASSERT_EQ(monitor.events().size(), 1u);
  const FaultEvent& e = monitor.events()[0];
  EXPECT_EQ(e.flag, kFaultJointTorqueLimit);
  EXPECT_EQ(e.joint, 3);
  EXPECT_GE(e.time, t_cross + 0.1 - 1e-9);
  EXPECT_LE(e.time, t_cross + 0.1 + dt + 1e-9);
  EXPECT_DOUBLE_EQ(e.limit, 25.7);
  EXPECT_NEAR(e.value, 100 * e.time, 1e-9);
  EXPECT_EQ(monitor.latched(), kFaultJointTorqueLimit);
}

// A run that drops below the limit before the hold time restarts the clock: 80 ms above, 1 ms
// below, 80 ms above: no event with a 0.1 s hold.
TEST(FaultMonitorTest, BrokenRunRestartsTheHold) {
  FaultMonitor monitor(Lander());
  const double dt = 1e-3;
  for (int k = 0; k < 161; ++k) {
    ArmSample s = Quiet(k * dt);
    s.joints[1].demanded = (k == 80) ? 100.0 : 150.0;  // effort 101
    monitor.Update(s);
  }
  EXPECT_TRUE(monitor.events().empty());
}

// Saturation is counted by the monitor alone (the arm driver's report reads it): j_shou_pitch
// (effort 101 N m) demanded 150 N m (and -150: |demanded| counts) at samples 10-89 and 120-129 of
// 1 ms steps, 101 N m exactly at sample 130 (at the limit counts), 100 N m elsewhere: its
// saturation time is the sum of the 91 samples' steps, 91 x 1e-3 s (to 1e-15 s), its first
// saturation the time of sample 10 exactly; every other joint 0 s and NaN; Reset() clears them.
TEST(FaultMonitorTest, SaturationTimeIsTheSumOfTheStepsAtOrAboveTheLimit) {
  FaultMonitor monitor(Lander());
  const double dt = 1e-3;
  for (int k = 0; k < 200; ++k) {
    ArmSample s = Quiet(k * dt);
    s.step = dt;
    const bool over = (k >= 10 && k < 90) || (k >= 120 && k < 130);
    s.joints[1].demanded = over ? (k % 2 ? 150.0 : -150.0) : k == 130 ? 101.0 : 100.0;
    monitor.Update(s);
  }
  ASSERT_EQ(monitor.saturation_time().size(), 6u);
  EXPECT_NEAR(monitor.saturation_time()[1], 91 * dt, 1e-15);
  EXPECT_EQ(monitor.first_saturation()[1], 10 * dt);
  for (int i : {0, 2, 3, 4, 5}) {
    EXPECT_EQ(monitor.saturation_time()[i], 0.0) << i;
    EXPECT_TRUE(std::isnan(monitor.first_saturation()[i])) << i;
  }
  monitor.Reset();
  EXPECT_EQ(monitor.saturation_time()[1], 0.0);
  EXPECT_TRUE(std::isnan(monitor.first_saturation()[1]));
}

// POSITION_LIMIT: j_shou_pitch (upper 2.2) at 2.25 raises it once (value 2.25, limit 2.2);
// a continuous joint at 7.88 rad (beyond its written +-3.2) does not.
TEST(FaultMonitorTest, PositionLimitOnRevoluteJointsOnly) {
  FaultMonitor monitor(Lander());
  ArmSample s = Quiet(0);
  s.joints[2].position = 7.88;
  EXPECT_EQ(monitor.Update(s).active, 0u);
  s.time = 0.001;
  s.joints[1].position = 2.25;
  EXPECT_EQ(monitor.Update(s).active, kFaultPositionLimit);
  s.time = 0.002;
  monitor.Update(s);
  ASSERT_EQ(monitor.events().size(), 1u);
  EXPECT_EQ(monitor.events()[0].joint, 1);
  EXPECT_DOUBLE_EQ(monitor.events()[0].value, 2.25);
  EXPECT_DOUBLE_EQ(monitor.events()[0].limit, 2.2);
}

// VELOCITY_LIMIT: |qd| > V (1 + 0.1): j_shou_yaw (V = 0.15) at 0.16 rad/s is within the margin,
// at 0.17 beyond 0.165: raised.
TEST(FaultMonitorTest, VelocityLimitWithMargin) {
  FaultMonitor monitor(Lander());
  ArmSample s = Quiet(0);
  s.joints[0].velocity = -0.16;
  EXPECT_EQ(monitor.Update(s).active, 0u);
  s.time = 0.001;
  s.joints[0].velocity = -0.17;
  EXPECT_EQ(monitor.Update(s).active, kFaultVelocityLimit);
  ASSERT_EQ(monitor.events().size(), 1u);
  EXPECT_DOUBLE_EQ(monitor.events()[0].value, 0.17);
  EXPECT_NEAR(monitor.events()[0].limit, 0.165, 1e-15);
}

// FORCE_TORQUE_LIMIT from the sensor at j_dist_pitch: |F| = 250 N >= 200 and later
// |T| = 120 N m >= 100 raise one event each; a sample without sensor data raises NO_FORCE_DATA.
TEST(FaultMonitorTest, ForceTorqueSensor) {
  FaultMonitor monitor(Lander());
  ArmSample s = Quiet(0);
  s.ft_force = Eigen::Vector3d(150, 0, 200);  // |F| = 250
  EXPECT_EQ(monitor.Update(s).active, kFaultForceTorqueLimit);
  s.time = 0.001;
  s.ft_torque = Eigen::Vector3d(0, 120, 0);
  monitor.Update(s);
  s.time = 0.002;
  s.has_ft = false;
  EXPECT_EQ(monitor.Update(s).active, kFaultNoForceData);
  ASSERT_EQ(monitor.events().size(), 3u);
  EXPECT_DOUBLE_EQ(monitor.events()[0].value, 250);
  EXPECT_DOUBLE_EQ(monitor.events()[0].limit, 200);
  EXPECT_EQ(monitor.events()[0].joint, 3);
  EXPECT_DOUBLE_EQ(monitor.events()[1].value, 120);
  EXPECT_DOUBLE_EQ(monitor.events()[1].limit, 100);
  EXPECT_EQ(monitor.events()[2].flag, kFaultNoForceData);
  EXPECT_EQ(monitor.latched(), kFaultForceTorqueLimit | kFaultNoForceData);
}

// Reactions: continue issues no command; stop-and-hold holds every joint where the event's
// sample had it; retract adds the scene's direction, distance and speed; a weaker or equal
// reaction later issues nothing new.
TEST(FaultMonitorTest, ReactionsCarryTheirData) {
  FaultRules rules;
  rules.on_velocity_limit = Reaction::kContinue;
  rules.on_position_limit = Reaction::kStopAndHold;
  rules.on_torque_limit = Reaction::kRetract;
  rules.torque_hold_time = 0;
  rules.retract_direction = Eigen::Vector3d(0, 0, 2);
  rules.retract_distance = 0.16;
  rules.retract_speed = 0.02;
  FaultMonitor monitor(Lander(), rules);

  ArmSample s = Quiet(0.5);
  s.joints[4].velocity = 1.0;  // VELOCITY_LIMIT: continue
  FaultStep step = monitor.Update(s);
  EXPECT_FALSE(step.new_command);
  EXPECT_EQ(monitor.command().kind, Reaction::kContinue);

  s = Quiet(0.6);
  for (int i = 0; i < 6; ++i) s.joints[i].position = 0.1 * i;
  s.joints[0].position = -1.6;  // POSITION_LIMIT: stop and hold
  step = monitor.Update(s);
  EXPECT_TRUE(step.new_command);
  EXPECT_EQ(monitor.command().kind, Reaction::kStopAndHold);
  EXPECT_EQ(monitor.command().flag, kFaultPositionLimit);
  EXPECT_DOUBLE_EQ(monitor.command().time, 0.6);
  ASSERT_EQ(monitor.command().hold_positions.size(), 6);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(monitor.command().hold_positions[i], s.joints[i].position);
  EXPECT_EQ(monitor.command().retract_distance, 0);

  s.time = 0.7;
  s.joints[5].demanded = 30;  // > 20: JOINT_TORQUE_LIMIT (hold 0): retract
  step = monitor.Update(s);
  EXPECT_TRUE(step.new_command);
  const ReactionCommand& c = monitor.command();
  EXPECT_EQ(c.kind, Reaction::kRetract);
  EXPECT_EQ(c.joint, 5);
  EXPECT_LT((c.retract_direction - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_EQ(c.retract_distance, 0.16);
  EXPECT_EQ(c.retract_speed, 0.02);

  s.time = 0.8;
  s.joints[1].position = 2.5;  // another POSITION_LIMIT: recorded, no new command
  step = monitor.Update(s);
  EXPECT_EQ(step.new_events, 1);
  EXPECT_FALSE(step.new_command);
  EXPECT_EQ(monitor.command().kind, Reaction::kRetract);
  EXPECT_STREQ(ReactionName(Reaction::kStopAndHold), "stop_and_hold");
}

// A fault that lasts one step between two rows (issue 40): samples every 1 ms, a row every 10
// samples (k = 9, 19, ...). With no hold time the demand on j_dist_pitch (effort 25.7 N m) is at
// 30 N m at sample 14 alone, so JOINT_TORQUE_LIMIT is active at that sample only. The condition at
// each row's instant (what the rows held before) is 0 at every row; the OR over the interval
// (RowFaultBits) puts bit 32 in the row of samples 10-19 and in no other.
TEST(FaultMonitorTest, OneStepFaultShowsInItsRow) {
  FaultRules rules;
  rules.torque_hold_time = 0;
  rules.on_torque_limit = Reaction::kContinue;
  FaultMonitor monitor(Lander(), rules);
  RowFaultBits row;
  std::vector<uint64_t> rows, at_row_instant;
  for (int k = 0; k < 40; ++k) {
    ArmSample s = Quiet(k * 1e-3);
    if (k == 14) s.joints[3].demanded = 30;
    const FaultStep step = monitor.Update(s);
    EXPECT_EQ(step.active, k == 14 ? uint64_t{kFaultJointTorqueLimit} : uint64_t{0})
        << "sample " << k;
    row.Add(step.active);
    if (k % 10 == 9) {
      rows.push_back(row.Take());
      at_row_instant.push_back(step.active);
    }
  }
  EXPECT_EQ(rows, (std::vector<uint64_t>{0, uint64_t{kFaultJointTorqueLimit}, 0, 0}));
  EXPECT_EQ(at_row_instant, (std::vector<uint64_t>{0, 0, 0, 0}));  // the old rows: no fault
  EXPECT_EQ(monitor.latched(), kFaultJointTorqueLimit);
}

TEST(FaultMonitorTest, UnknownSensorJointIsRejected) {
  FaultRules rules;
  rules.ft_joint = "j_elbow";
  EXPECT_THROW(FaultMonitor(Lander(), rules), std::invalid_argument);
}

}  // namespace
}  // namespace arm

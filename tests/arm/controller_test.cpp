// Tests of arm/controller.cpp: the torque saturation rule, the PID's closed form, inverse
// kinematics and pose paths under joint and velocity limits.
#include "arm/controller.h"

#include <gtest/gtest.h>

#include "arm/kinematics.h"

namespace arm {
namespace {

const ArmModel& Lander() {
  static const ArmModel model = LoadArmModel(ARM_TEST_URDF);
  return model;
}

Eigen::VectorXd Digging() { return Eigen::Map<const Eigen::VectorXd>(kLanderPoses[3].q.data(), 6); }

// The scoop moving along base x at `speed` [m/s] from its digging pose, orientation kept:
// samples every dt [s] up to `duration` [s].
std::vector<PosePoint> LinePath(double speed, double dt, double duration) {
  const Eigen::Isometry3d start = LinkPose(Lander(), Digging(), "l_scoop");
  std::vector<PosePoint> path;
  for (int k = 0; k * dt <= duration + 1e-12; ++k) {
    PosePoint p;
    p.time = k * dt;
    p.pose = start;
    p.pose.translation().x() += speed * p.time;
    path.push_back(p);
  }
  return path;
}

// applied = clamp(demanded, +-effort), then no torque toward an exceeded velocity limit (Gazebo's
// Joint::CheckAndTruncateForce). Exact.
TEST(ControllerTest, SaturationRule) {
  const Joint& j = Lander().joints[0];  // effort 70.9, velocity 0.15
  EXPECT_EQ(LimitTorque(50, 0, j), 50);
  EXPECT_EQ(LimitTorque(100, 0, j), 70.9);
  EXPECT_EQ(LimitTorque(-100, 0, j), -70.9);
  EXPECT_EQ(LimitTorque(30, 0.16, j), 0);       // pushing on past +limit: cut
  EXPECT_EQ(LimitTorque(-30, 0.16, j), -30);    // braking: kept
  EXPECT_EQ(LimitTorque(-30, -0.16, j), 0);     // pushing on past -limit: cut
  EXPECT_EQ(LimitTorque(100, -0.16, j), 70.9);  // braking, clamped
  EXPECT_EQ(LimitTorque(30, 0.15, j), 30);      // at the limit, not past it
}

// One step of the PID: demanded = p e + i (e dt) + d (qd_ref - qd), applied = its clamp; the
// demanded torque is logged unclamped. Exact to rounding (1e-12).
TEST(ControllerTest, PidClosedFormAndClamp) {
  const ArmModel& m = Lander();
  JointPid pid(m, LanderGains());
  Eigen::VectorXd q_ref = Eigen::VectorXd::Zero(6), qd_ref = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6), qd = Eigen::VectorXd::Zero(6);
  q_ref[1] = 0.001;  // small: not saturated
  q_ref[3] = 0.1;    // 2000 * 0.1 = 200 N m > 25.7: saturated
  qd[1] = 0.01;
  const double dt = 1e-3;
  Eigen::VectorXd demanded, applied;
  pid.Compute(q_ref, qd_ref, q, qd, dt, &demanded, &applied);
  const double d1 = 20000 * 0.001 + 0.2 * 0.001 * dt + 150 * (0 - 0.01);
  EXPECT_NEAR(demanded[1], d1, 1e-12);
  EXPECT_NEAR(applied[1], d1, 1e-12);
  const double d3 = 2000 * 0.1 + 0.06 * 0.1 * dt;
  EXPECT_NEAR(demanded[3], d3, 1e-12);
  EXPECT_EQ(applied[3], 25.7);
  // A second step accumulates the integral: i * (2 e dt).
  pid.Compute(q_ref, qd_ref, q, qd, dt, &demanded, &applied);
  EXPECT_NEAR(demanded[3], 2000 * 0.1 + 0.06 * 0.1 * 2 * dt, 1e-12);
  EXPECT_THROW(JointPid(m, std::vector<PidGains>(5)), std::invalid_argument);
}

// The implicit form of the same step: bias = p e + i (e dt) + d qd_ref, gain d, bounds +-effort,
// the bound toward an exceeded velocity limit 0; demanded(v) = bias - d v equals the explicit
// PID's output at qd = v. Exact to rounding (1e-12).
TEST(ControllerTest, ServoClosedForm) {
  const ArmModel& m = Lander();
  JointPid pid(m, LanderGains()), explicit_pid(m, LanderGains());
  Eigen::VectorXd q_ref = Eigen::VectorXd::Zero(6), qd_ref = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6), qd = Eigen::VectorXd::Zero(6);
  q_ref[1] = 0.001;
  qd_ref[1] = 0.02;
  qd[2] = 0.25;  // past j_prox_pitch's 0.2 rad/s: no positive torque
  qd[4] = -0.3;  // past -0.2 on j_hand_yaw: no negative torque
  const double dt = 1e-3;
  JointServo servo;
  pid.ComputeServo(q_ref, qd_ref, q, qd, dt, &servo);
  EXPECT_NEAR(servo.bias[1], 20000 * 0.001 + 0.2 * 0.001 * dt + 150 * 0.02, 1e-12);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(servo.gain[i], kLanderGains[i].d);
  EXPECT_EQ(servo.upper[2], 0);
  EXPECT_EQ(servo.lower[2], -73.0);
  EXPECT_EQ(servo.lower[4], 0);
  EXPECT_EQ(servo.upper[4], 25.7);
  EXPECT_EQ(servo.upper[1], 101.0);
  Eigen::VectorXd v(6), demanded, explicit_demanded, applied;
  v << 0.01, -0.02, 0.03, 0.0, 0.05, -0.01;
  JointPid::Demanded(servo, v, &demanded);
  explicit_pid.Compute(q_ref, qd_ref, q, v, dt, &explicit_demanded, &applied);
  EXPECT_LT((demanded - explicit_demanded).cwiseAbs().maxCoeff(), 1e-12);
}

// IK from another pose reaches a reachable target: the pose of l_scoop at known angles, within
// the tolerances asked (1e-6 m, 1e-5 rad).
TEST(ControllerTest, IkReachesAReachablePose) {
  const ArmModel& m = Lander();
  Eigen::VectorXd target_q = Digging();
  target_q[0] += 0.2;
  target_q[2] -= 0.15;
  target_q[4] += 0.3;
  const Eigen::Isometry3d target = LinkPose(m, target_q, "l_scoop");
  const IkResult r = SolveIk(m, "l_scoop", target, Digging());
  EXPECT_TRUE(r.converged) << r.position_error << " m, " << r.angle_error << " rad";
  EXPECT_LE(r.position_error, 1e-6);
  EXPECT_LE(r.angle_error, 1e-5);
}

// A target beyond j_shou_yaw's range (-1.56, 1.43): IK stops at the limit, never past it.
TEST(ControllerTest, IkRespectsJointLimits) {
  const ArmModel& m = Lander();
  Eigen::VectorXd beyond = Digging();
  beyond[0] = 2.0;
  const IkResult r = SolveIk(m, "l_scoop", LinkPose(m, beyond, "l_scoop"), Digging());
  EXPECT_FALSE(r.converged);
  EXPECT_GE(r.q[0], m.joints[0].lower);
  EXPECT_LE(r.q[0], m.joints[0].upper);
  EXPECT_GE(r.q[1], m.joints[1].lower);
  EXPECT_LE(r.q[1], m.joints[1].upper);
}

// A straight 0.1 m line of the scoop along base x at 5 mm/s, 0.1 s samples, orientation kept:
// the joint references follow it within 1e-5 m and 1e-4 rad, no velocity limit binds, and
// every step stays within velocity_i dt.
TEST(ControllerTest, PosePathFollowedWithinVelocityLimits) {
  const ArmModel& m = Lander();
  const std::vector<PosePoint> path = LinePath(0.005, 0.1, 20);
  const JointPath jp = FollowPosePath(m, "l_scoop", path, Digging());
  EXPECT_EQ(jp.velocity_limited, 0);
  EXPECT_LE(jp.max_position_error, 1e-5);
  EXPECT_LE(jp.max_angle_error, 1e-4);
  for (size_t k = 1; k < jp.q.size(); ++k) {
    for (int i = 0; i < 6; ++i) {
      EXPECT_LE(std::abs(jp.q[k][i] - jp.q[k - 1][i]), m.joints[i].velocity * 0.1 + 1e-12);
    }
  }
}

// The same line at 0.3 m/s (the study's Table 1 speed) asks more than the joints' 0.15-0.2
// rad/s: the references are held to |dq_i| <= velocity_i dt, and the error says so.
TEST(ControllerTest, FastPathIsHeldToTheVelocityLimits) {
  const ArmModel& m = Lander();
  const std::vector<PosePoint> path = LinePath(0.3, 0.05, 1);
  const JointPath jp = FollowPosePath(m, "l_scoop", path, Digging());
  EXPECT_GT(jp.velocity_limited, 0);
  EXPECT_GT(jp.max_position_error, 0.05);
  for (size_t k = 1; k < jp.q.size(); ++k) {
    for (int i = 0; i < 6; ++i) {
      EXPECT_LE(std::abs(jp.q[k][i] - jp.q[k - 1][i]), m.joints[i].velocity * 0.05 + 1e-12);
    }
  }
}

}  // namespace
}  // namespace arm

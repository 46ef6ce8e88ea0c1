// Tests of arm/bullet_arm.cpp: Bullet's btMultiBody against the arm's own Eigen maths
// (arm/kinematics.cpp) and against closed forms.
#include "arm/bullet_arm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "arm/controller.h"
#include "arm/fault_monitor.h"
#include "arm/kinematics.h"

namespace arm {
namespace {

const ArmModel& Lander() {
  static const ArmModel model = LoadArmModel(ARM_TEST_URDF);
  return model;
}

Eigen::VectorXd Pose(const char* name) {
  for (const NamedPose& p : kLanderPoses) {
    if (std::string(p.name) == name) return Eigen::Map<const Eigen::VectorXd>(p.q.data(), 6);
  }
  return Eigen::VectorXd::Zero(6);
}

// Options with gravity (0, 0, -1.3 m/s^2) or none, joint damping and friction on or off.
BulletArmOptions Options(bool gravity, bool damping, bool friction) {
  BulletArmOptions options;
  options.gravity = gravity ? Eigen::Vector3d(0, 0, -1.3) : Eigen::Vector3d::Zero();
  options.joint_damping = damping;
  options.joint_friction = friction;
  return options;
}

double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(Eigen::Matrix3d(a * b.transpose())).angle();
}

// Bullet's link poses, read through the stored principal-axes transforms, are the URDF link
// frames of our own forward kinematics (1e-12 m, 1e-12 rad), at random joint angles.
TEST(BulletArmTest, LinkPosesMatchForwardKinematics) {
  const ArmModel& m = Lander();
  BulletArm arm(m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = u(rng);
    arm.SetJointState(q);
    const auto poses = BodyPoses(m, q);
    for (int b = 0; b <= 6; ++b) {
      EXPECT_LT((arm.BodyPose(b).translation() - poses[b].translation()).norm(), 1e-12);
      EXPECT_LT(AngleBetween(arm.BodyPose(b).linear(), poses[b].linear()), 1e-12);
    }
    EXPECT_LT(
        (arm.LinkPose("l_scoop_tip").translation() - LinkPose(m, q, "l_scoop_tip").translation())
            .norm(),
        1e-12);
  }
}

// l_scoop's principal axes: its inertia has Ixz = 0.000158 (Ixy = Iyz = 0), so one principal axis
// is y and the others are turned about y by 0.5 atan2(2 Ixz, Ixx - Izz) = 17.8 degrees from x
// and z (FACTS: "about 18 degrees"); Bullet's link frame is that, at the CoM (1e-12).
TEST(BulletArmTest, ScoopFrameIsTurnedOntoItsPrincipalAxes) {
  const ArmModel& m = Lander();
  BulletArm arm(m);
  const Eigen::Isometry3d& p = arm.PrincipalFrame(6);
  EXPECT_LT((p.translation() - Eigen::Vector3d(0.001315, 0, 0.045328)).norm(), 1e-15);
  const double expected = 0.5 * std::atan2(2 * 0.000158, 0.001031 - 0.000591);
  EXPECT_NEAR(expected * 180 / M_PI, 17.8, 0.05);
  double closest_to_x = M_PI;
  for (int c = 0; c < 3; ++c) {
    const Eigen::Vector3d axis = p.linear().col(c);
    closest_to_x = std::min(closest_to_x, std::acos(std::min(1.0, std::abs(axis.x()))));
  }
  EXPECT_NEAR(closest_to_x, expected, 1e-9);
  // The principal moments reproduce the inertia: R diag(I) R^T = I_urdf.
  const Eigen::Matrix3d back =
      p.linear() * arm.PrincipalMoments(6).asDiagonal() * p.linear().transpose();
  EXPECT_LT((back - m.bodies[6].inertial.inertia).norm(), 1e-15);
  // Bullet's own link frame sits on the CoM with those axes.
  arm.SetJointState(Pose("digging"));
  const Eigen::Isometry3d expected_frame = arm.BodyPose(6) * p;
  EXPECT_LT((arm.BulletLinkFrame(6).translation() - expected_frame.translation()).norm(), 1e-12);
  EXPECT_LT(AngleBetween(arm.BulletLinkFrame(6).linear(), expected_frame.linear()), 1e-12);
}

// Twists read from Bullet equal J(q) qd of our own Jacobian (1e-12).
TEST(BulletArmTest, TwistsMatchTheJacobian) {
  const ArmModel& m = Lander();
  BulletArm arm(m);
  Eigen::VectorXd q = Pose("digging"), qd(6);
  qd << 0.1, -0.2, 0.15, 0.3, -0.25, 0.2;
  arm.SetJointState(q, qd);
  for (const char* link : {"l_prox", "l_scoop", "l_scoop_tip"}) {
    int body = 0;
    m.FindLink(link, &body, nullptr);
    const Eigen::Vector3d origin = LinkPose(m, q, link).translation();
    const Eigen::Matrix<double, 6, 1> v = PointJacobian(m, q, body, origin) * qd;
    const Twist t = arm.LinkTwist(link);
    EXPECT_LT((t.linear - v.head<3>()).norm(), 1e-12) << link;
    EXPECT_LT((t.angular - v.tail<3>()).norm(), 1e-12) << link;
  }
}

// Forward dynamics: joint torques from our Newton-Euler for a chosen qdd, at a moving state,
// applied in Bullet (no damping or friction) give that qdd over one step: Bullet's semi-implicit
// Euler makes (qd1 - qd0) / dt exactly its acceleration at the start state. 1e-8 relative.
TEST(BulletArmTest, BulletDynamicsMatchNewtonEuler) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(true, false, false);
  BulletArm arm(m, options);
  Eigen::VectorXd q = Pose("unstowed"), qd(6), qdd(6);
  qd << 0.3, -0.2, 0.25, -0.4, 0.5, 0.6;
  qdd << 1.0, -0.5, 2.0, -3.0, 4.0, 5.0;
  arm.SetJointState(q, qd);
  arm.SetJointTorques(InverseDynamics(m, q, qd, qdd, options.gravity));
  arm.Step(1e-4);
  EXPECT_LT((arm.qdd() - qdd).norm(), 1e-8 * qdd.norm()) << arm.qdd().transpose();
}

// Holds the arm at `pose` with the lander's PID (dt = 5e-5 s) until steady; returns the applied
// torques, with the final joint angles in *q_final. Starts near the static equilibrium the P term
// allows (q = pose - P^-1 tau_hold(q), a few fixed-point sweeps), so the transient is small.
Eigen::VectorXd HoldSteady(BulletArm* arm, const Eigen::VectorXd& pose,
                           const std::vector<BodyWrench>& loads, double seconds,
                           Eigen::VectorXd* q_final) {
  const ArmModel& m = arm->model();
  JointPid pid(m, LanderGains());
  Eigen::VectorXd start = pose;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(6);
  for (int sweep = 0; sweep < 5; ++sweep) {
    std::vector<BodyWrench> moved = loads;
    for (BodyWrench& w : moved) {
      w.wrench.point =
          BodyPoses(m, start)[w.body] * (BodyPoses(m, pose)[w.body].inverse() * w.wrench.point);
    }
    const Eigen::VectorXd hold = InverseDynamics(m, start, zero, zero, arm->gravity(), moved);
    for (int i = 0; i < 6; ++i) start[i] = pose[i] - hold[i] / kLanderGains[i].p;
  }
  arm->SetJointState(start);
  Eigen::VectorXd demanded, applied;
  const double dt = 5e-5;
  const int steps = static_cast<int>(seconds / dt);
  for (int k = 0; k < steps; ++k) {
    pid.Compute(pose, zero, arm->q(), arm->qd(), dt, &demanded, &applied);
    arm->SetJointTorques(applied);
    for (const BodyWrench& w : loads) {
      // The wrench stays on the same material point: its torque point moves with the body.
      Wrench moved = w.wrench;
      moved.point = arm->BodyPose(w.body) * (BodyPoses(m, pose)[w.body].inverse() * w.wrench.point);
      arm->ApplyWrench(w.body, moved);
    }
    arm->Step(dt);
  }
  // Steady: what is left is the integral term's creep, qd ~ i e / p ~ 2e-6 rad/s on j_shou_yaw
  // under the wrench (a time constant p / i = 830 s), which moves the torques by ~1e-5 N m/s.
  EXPECT_LT(arm->qd().cwiseAbs().maxCoeff(), 1e-5) << "not steady: " << arm->qd().transpose();
  EXPECT_TRUE((applied.array() == demanded.array()).all()) << "saturated";
  *q_final = arm->q();
  return applied;
}

// |a_i - b_i| <= 1% of |b_i|, or 1% of max |b| for a joint that carries almost none (the
// shoulder yaw, whose axis is vertical).
void ExpectWithinOnePercent(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                            const std::string& what) {
  const double floor = 0.01 * b.cwiseAbs().maxCoeff();
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_LE(std::abs(a[i] - b[i]), std::max(0.01 * std::abs(b[i]), floor))
        << what << " joint " << i << ": " << a[i] << " vs " << b[i];
  }
}

// Gravity alone (1.3 m/s^2), arm held by the lander's PID at three poses: Bullet's steady applied
// joint torques equal the gravity torques of our own Newton-Euler from the URDF inertials, at the
// joint angles reached, within 1%. Coulomb friction is off here: at rest it holds any torque
// within +-friction, so the steady torque is defined only without it.
TEST(BulletArmTest, SteadyTorquesEqualGravityTorques) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(true, true, false);
  for (const char* name : {"unstowed", "digging", "zero"}) {
    BulletArm arm(m, options);
    Eigen::VectorXd q;
    const Eigen::VectorXd applied = HoldSteady(&arm, Pose(name), {}, 1.0, &q);
    const Eigen::VectorXd gravity = GravityTorques(m, q, options.gravity);
    ExpectWithinOnePercent(applied, gravity, name);
    const double worst = ((applied - gravity).cwiseAbs().array() /
                          gravity.cwiseAbs().array().max(0.01 * gravity.cwiseAbs().maxCoeff()))
                             .maxCoeff();
    RecordProperty(std::string("worst_relative_") + name, std::to_string(worst));
    std::printf("[ info ] %s: worst relative difference %.2e\n", name, worst);
  }
}

// A known wrench W on the scoop (force at l_scoop_tip, torque) changes the steady joint torques
// by -J^T W (the torques that hold it), J the Jacobian of that point at the angles reached:
// applied - G(q) = -J(q)^T W within 1%.
TEST(BulletArmTest, WrenchOnScoopChangesTorquesByJacobianTranspose) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(true, true, false);
  BulletArm arm(m, options);
  const Eigen::VectorXd pose = Pose("digging");
  Wrench w;
  w.force = Eigen::Vector3d(15, -5, 25);
  w.torque = Eigen::Vector3d(0.6, -0.4, 0.5);
  w.point = LinkPose(m, pose, "l_scoop_tip").translation();
  Eigen::VectorXd q;
  const Eigen::VectorXd applied = HoldSteady(&arm, pose, {{6, w}}, 1.0, &q);
  Wrench reached = w;
  reached.point = LinkPose(m, q, "l_scoop_tip").translation();
  Eigen::Matrix<double, 6, 1> wv;
  wv << w.force, w.torque;
  const Eigen::VectorXd jtw = PointJacobian(m, q, 6, reached.point).transpose() * wv;
  const Eigen::VectorXd change = applied - GravityTorques(m, q, options.gravity);
  ExpectWithinOnePercent(change, -jtw, "J^T W");
  const double worst = ((change + jtw).cwiseAbs().array() /
                        jtw.cwiseAbs().array().max(0.01 * jtw.cwiseAbs().maxCoeff()))
                           .maxCoeff();
  std::printf("[ info ] J^T W: worst relative difference %.2e\n", worst);
}

// A URDF of one continuous joint j_NAME from base_link to l_NAME: the joint's origin attributes,
// axis and limit attributes, and the child's inertial (CoM, mass, inertia attributes).
std::string OneJointUrdf(const std::string& name, const std::string& origin,
                         const std::string& axis, const std::string& limit, const std::string& com,
                         double mass, const std::string& inertia) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"" + name +
         "\">\n  <link name=\"base_link\"/>\n  <joint name=\"j_" + name +
         "\" type=\"continuous\">\n    <parent link=\"base_link\"/><child link=\"l_" + name +
         "\"/>\n    <origin " + origin + "/>\n    <axis xyz=\"" + axis + "\"/>\n    <limit " +
         limit + "/>\n  </joint>\n  <link name=\"l_" + name +
         "\">\n    <inertial>\n      <origin xyz=\"" + com +
         "\" rpy=\"0 0 0\"/>\n      <mass value=\"" + std::to_string(mass) +
         "\"/>\n      <inertia " + inertia + "/>\n    </inertial>\n  </link>\n</robot>";
}

// One link whose inertia has off-diagonal terms, hinged about an axis that is no principal or
// coordinate axis, swinging freely under gravity from rest: theta'' = tau_g(theta) / I_a with
// I_a = a' (I_c + m (|r|^2 1 - r r')) a and tau_g = a . (r(theta) x m g), integrated by RK4 at
// 1e-5 s. Bullet (1e-4 s, no damping or friction) follows it within 1% of the swing's amplitude
// over one period. Leaving out the off-diagonal terms would change I_a by more than 5%.
TEST(BulletArmTest, FreeSwingOfAnOffDiagonalLinkMatchesOwnIntegration) {
  const std::string urdf =
      OneJointUrdf("swing", R"(xyz="0.1 0.2 0.3" rpy="0.3 -0.2 0.5")", "0.48 0.8 0.36",
                   R"(effort="10" velocity="10")", "0.02 -0.01 -0.08", 2.0,
                   R"(ixx="0.05" ixy="0.015" ixz="-0.012" iyy="0.045" iyz="0.01" izz="0.04")");
  const ArmModel m = ParseArmModel(urdf, "swing.urdf", "l_swing");
  const Eigen::Vector3d g(0, 0, -1.3);
  // Closed-form ingredients, world axes at theta = 0.
  const Eigen::Isometry3d joint = m.joints[0].origin;
  const Eigen::Vector3d a = joint.linear() * m.joints[0].axis;
  const Eigen::Vector3d r0 = joint.linear() * m.bodies[1].inertial.com;
  const Eigen::Matrix3d ic =
      joint.linear() * m.bodies[1].inertial.inertia * joint.linear().transpose();
  const double mass = m.bodies[1].inertial.mass;
  auto inertia_about_axis = [&](const Eigen::Matrix3d& i) {
    return a.dot(
        (i + mass * (r0.squaredNorm() * Eigen::Matrix3d::Identity() - r0 * r0.transpose())) * a);
  };
  const double ia = inertia_about_axis(ic);
  const Eigen::Matrix3d ic_diag = Eigen::Matrix3d(Eigen::Vector3d(0.05, 0.045, 0.04).asDiagonal());
  const double ia_diag = inertia_about_axis(joint.linear() * ic_diag * joint.linear().transpose());
  EXPECT_GT(std::abs(ia - ia_diag) / ia, 0.05) << "the test would not see the off-diagonals";
  auto accel = [&](double theta) {
    const Eigen::Vector3d r = Eigen::AngleAxisd(theta, a) * r0;
    return a.dot(r.cross(mass * g)) / ia;
  };
  // Reference: RK4 from rest at theta = 0 until the swing returns (one period).
  const double h = 1e-5;
  std::vector<double> ref_theta{0};
  double th = 0, om = 0;
  int sign_changes = 0;
  double prev_om = 0;
  for (int k = 0; k < 2000000 && sign_changes < 2; ++k) {
    const double k1t = om, k1o = accel(th);
    const double k2t = om + 0.5 * h * k1o, k2o = accel(th + 0.5 * h * k1t);
    const double k3t = om + 0.5 * h * k2o, k3o = accel(th + 0.5 * h * k2t);
    const double k4t = om + h * k3o, k4o = accel(th + h * k3t);
    th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    om += h / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    if (k > 0 && ((om > 0) != (prev_om > 0))) ++sign_changes;
    prev_om = om;
    ref_theta.push_back(th);
  }
  ASSERT_EQ(sign_changes, 2);
  const double period = h * (ref_theta.size() - 1);
  double lo = 0, hi = 0;
  for (double t : ref_theta) {
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  const double amplitude = hi - lo;
  ASSERT_GT(amplitude, 0.5);
  // Bullet.
  const BulletArmOptions options = Options(true, false, false);
  BulletArm arm(m, options);
  arm.SetJointState(Eigen::VectorXd::Zero(1));
  const double dt = 1e-4;
  const int steps = static_cast<int>(period / dt);
  double worst = 0;
  for (int k = 1; k <= steps; ++k) {
    arm.Step(dt);
    const size_t at = static_cast<size_t>(std::llround(k * dt / h));
    worst = std::max(worst, std::abs(arm.q()[0] - ref_theta[at]));
  }
  EXPECT_LE(worst, 0.01 * amplitude) << "period " << period << " s, amplitude " << amplitude;
  std::printf("[ info ] period %.4f s, amplitude %.3f rad, worst difference %.2e of it\n", period,
              amplitude, worst / amplitude);
}

// Kinetic energy of the arm's bodies from our own kinematics [J].
double KineticEnergy(const ArmModel& m, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  const auto poses = BodyPoses(m, q);
  double e = 0;
  for (int b = 1; b <= m.dof(); ++b) {
    const Inertial& in = m.bodies[b].inertial;
    const Eigen::Matrix<double, 6, 1> v = PointJacobian(m, q, b, poses[b] * in.com) * qd;
    const Eigen::Matrix3d iw = poses[b].linear() * in.inertia * poses[b].linear().transpose();
    e += 0.5 * in.mass * v.head<3>().squaredNorm() + 0.5 * v.tail<3>().dot(iw * v.tail<3>());
  }
  return e;
}

// Damping is implicit: j_scoop_yaw alone moving (damping 50 N m s/rad, inertia ~6e-4 kg m^2) at
// dt = 1e-3 s, 40 times the explicit limit 2 I / c (there each step would multiply its rate by
// about 1 - dt c / I = -80): its rate decays without changing sign, the arm's kinetic energy
// never grows, and after 0.5 s the energy is below 1e-4 of its start (what is left is the slow
// decay of the heavy inner joints the coupling set moving, c / I ~ 10 /s).
TEST(BulletArmTest, JointDampingIsStableAtLargeSteps) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(false, true, false);
  BulletArm arm(m, options);
  Eigen::VectorXd qd = Eigen::VectorXd::Zero(6);
  qd[5] = 0.2;
  arm.SetJointState(Pose("digging"), qd);
  const double e0 = KineticEnergy(m, arm.q(), arm.qd());
  double previous = e0;
  for (int k = 0; k < 500; ++k) {
    arm.Step(1e-3);
    EXPECT_GE(arm.qd()[5], 0) << "step " << k;
    const double e = KineticEnergy(m, arm.q(), arm.qd());
    EXPECT_LE(e, previous * (1 + 1e-12)) << "step " << k;
    previous = e;
  }
  EXPECT_LT(previous, 1e-4 * e0);
}

// Coulomb friction, from rest, no gravity, no damping. A torque of 0.4 N m on j_scoop_yaw
// (friction 0.5 N m) leaves the arm still (rates below 1e-15 rad/s: the friction torque is
// applied as a torque, exact to rounding). 0.6 N m slides it while the other joints stay stuck
// (their friction holds the reaction, at most 0.14 N m here): the closed form for one step is
// then qd_6 = dt (0.6 - 0.5) / I_6, I_6 the scoop's inertia about the j_scoop_yaw axis from its
// URDF inertial, a' (I_c + m (|r|^2 1 - r r')) a; 1e-9 relative.
TEST(BulletArmTest, CoulombFrictionHoldsThenSubtracts) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(false, false, true);
  BulletArm arm(m, options);
  const Eigen::VectorXd q = Pose("digging");
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(6);
  arm.SetJointState(q);
  tau[5] = 0.4;
  for (int k = 0; k < 100; ++k) {
    arm.SetJointTorques(tau);
    arm.Step(1e-3);
  }
  EXPECT_LT(arm.qd().cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((arm.q() - q).cwiseAbs().maxCoeff(), 1e-15);

  arm.SetJointState(q);
  tau[5] = 0.6;
  arm.SetJointTorques(tau);
  const double dt = 1e-3;
  arm.Step(dt);
  const Inertial& in = m.bodies[6].inertial;  // in the l_scoop frame; the axis is its -z
  const Eigen::Vector3d a = m.joints[5].axis, r = in.com;
  const double i6 = a.dot(
      (in.inertia + in.mass * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose())) *
      a);
  EXPECT_NEAR(arm.qd()[5], dt * 0.1 / i6, 1e-9 * dt * 0.1 / i6);
  EXPECT_LT(arm.qd().head<5>().cwiseAbs().maxCoeff(), 1e-15);
}

// addLinkForce/addLinkTorque are cleared every step: a wrench given once acts on one step only.
// Two arms in the same state after that step, one of them given nothing more, step alike.
TEST(BulletArmTest, WrenchActsForOneStepOnly) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(false, false, false);
  BulletArm a(m, options), b(m, options);
  a.SetJointState(Pose("digging"));
  Wrench w;
  w.force = Eigen::Vector3d(0, 0, 50);
  w.point = a.LinkPose("l_scoop_tip").translation();
  a.ApplyWrench(6, w);
  a.Step(1e-3);
  EXPECT_GT(a.qd().norm(), 1e-4);
  b.SetJointState(a.q(), a.qd());
  a.Step(1e-3);
  b.Step(1e-3);
  EXPECT_LT((a.qd() - b.qd()).norm(), 1e-14);
}

// A rotor: one continuous joint about z, its CoM on the axis, inertia I = 0.01 kg m^2 about
// it, effort limit `effort` [N m], velocity limit `velocity` [rad/s], no damping or friction.
ArmModel Rotor(double effort, double velocity = 100) {
  const std::string urdf = OneJointUrdf(
      "rotor", R"(xyz="0 0 0" rpy="0 0 0")", "0 0 1",
      "effort=\"" + std::to_string(effort) + "\" velocity=\"" + std::to_string(velocity) + "\"",
      "0 0 0", 1.0, R"(ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01")");
  return ParseArmModel(urdf, "rotor.urdf", "l_rotor");
}

// The PD step response of I theta'' = p (theta_ref - theta) - d theta' from rest, closed form:
// omega = sqrt(p / I), zeta = d / (2 sqrt(p I)).
double StepResponse(double t, double inertia, double p, double d, double theta_ref) {
  const double w = std::sqrt(p / inertia), z = d / (2 * std::sqrt(p * inertia));
  if (z < 1) {
    const double wd = w * std::sqrt(1 - z * z);
    return theta_ref * (1 - std::exp(-z * w * t) *
                                (std::cos(wd * t) + z / std::sqrt(1 - z * z) * std::sin(wd * t)));
  }
  const double s = std::sqrt(z * z - 1), r1 = -z * w + w * s, r2 = -z * w - w * s;
  return theta_ref * (1 - (r2 * std::exp(r1 * t) - r1 * std::exp(r2 * t)) / (r2 - r1));
}

// Runs the rotor's PD (p, i = 0, d) toward a step of 0.1 rad from rest for `seconds` at step dt,
// the D term implicit (ComputeServo) or explicit (Compute); returns max |theta - closed form| /
// 0.1 rad, or infinity once |theta| passes 10 rad (diverged). Effort and velocity limits far
// away (1e9): nothing clamps.
double RotorStepError(double p, double d, double dt, double seconds, bool implicit,
                      bool* overshoot = nullptr) {
  const ArmModel m = Rotor(1e9, 1e9);
  BulletArm arm(m, Options(false, false, false));
  JointPid pid(m, {{p, 0, d}});
  const Eigen::VectorXd ref = Eigen::VectorXd::Constant(1, 0.1), zero = Eigen::VectorXd::Zero(1);
  Eigen::VectorXd demanded, applied;
  JointServo servo;
  double worst = 0;
  if (overshoot) *overshoot = false;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int k = 1; k <= steps; ++k) {
    if (implicit) {
      pid.ComputeServo(ref, zero, arm.q(), arm.qd(), dt, &servo);
      arm.SetJointServo(servo);
    } else {
      pid.Compute(ref, zero, arm.q(), arm.qd(), dt, &demanded, &applied);
      arm.SetJointTorques(applied);
    }
    arm.Step(dt);
    if (!(std::abs(arm.q()[0]) < 10)) return std::numeric_limits<double>::infinity();
    if (overshoot && arm.q()[0] > 0.1) *overshoot = true;
    worst = std::max(worst, std::abs(arm.q()[0] - StepResponse(k * dt, 0.01, p, d, 0.1)) / 0.1);
  }
  return worst;
}

// The PID's D term implicit (BulletArm's servo) against the closed-form step response of a PD
// joint, I = 0.01 kg m^2, p = 100 N m/rad (omega = 100 rad/s). Underdamped (d = 1, zeta = 0.5) at
// dt = 1e-4 s: within 0.3% of the step over 0.3 s (semi-implicit Euler's error is first order,
// ~omega dt / 6 of the step here: 0.16%). Overdamped (d = 10, zeta = 5) at the lander's 400 Hz,
// dt = 2.5e-3 s, 1.25 x the explicit D term's bound 2 I / d = 2e-3 s: the explicit one diverges,
// the implicit one follows the closed form within 0.6% of the step over 0.5 s (first order
// again: 0.46%) and never overshoots, as the closed form does not.
TEST(BulletArmTest, ImplicitDTermTracksTheClosedFormStepResponseAndIsStableAtLargeSteps) {
  const double under = RotorStepError(100, 1, 1e-4, 0.3, true);
  EXPECT_LT(under, 3e-3);
  bool overshoot = true;
  const double over = RotorStepError(100, 10, 2.5e-3, 0.5, true, &overshoot);
  EXPECT_LT(over, 6e-3);
  EXPECT_FALSE(overshoot);
  EXPECT_TRUE(std::isinf(RotorStepError(100, 10, 2.5e-3, 0.5, false)));
  // The explicit one within its bound agrees with the closed form too (the test's own check).
  EXPECT_LT(RotorStepError(100, 10, 1e-4, 0.5, false), 3e-3);
  std::printf("[ info ] implicit D: zeta 0.5 at 1e-4 s %.2e, zeta 5 at 2.5e-3 s %.2e of the step\n",
              under, over);
}

// A saturated servo gives exactly its bound: the rotor's effort limit 5 N m against a demanded
// 10 N m (p = 100 on a 0.1 rad error): one step from rest reaches v = dt 5 / I, the applied
// torque is 5 and the demanded 10 - d v. With qd past the velocity limit the bound toward it is
// 0 (LimitTorque's rule): the servo brakes only.
TEST(BulletArmTest, SaturatedServoGivesExactlyItsBound) {
  const ArmModel m = Rotor(5);
  BulletArm arm(m, Options(false, false, false));
  JointPid pid(m, {{100, 0, 1}});
  const Eigen::VectorXd ref = Eigen::VectorXd::Constant(1, 0.1), zero = Eigen::VectorXd::Zero(1);
  JointServo servo;
  const double dt = 1e-3;
  pid.ComputeServo(ref, zero, arm.q(), arm.qd(), dt, &servo);
  arm.SetJointServo(servo);
  arm.Step(dt);
  EXPECT_NEAR(arm.qd()[0], dt * 5 / 0.01, 1e-15);
  EXPECT_EQ(arm.motor_torques()[0], 5);
  Eigen::VectorXd demanded;
  JointPid::Demanded(servo, arm.qd(), &demanded);
  EXPECT_NEAR(demanded[0], 10 - 1 * arm.qd()[0], 1e-12);

  // Past the velocity limit (101 > 100 rad/s) with a demand that pushes on (p x 1000 rad): cut
  // to 0, the rotor coasts; with one that brakes (the 0.1 rad step: 10 - 101 d < 0), -5.
  arm.SetJointState(zero, Eigen::VectorXd::Constant(1, 101.0));
  pid.ComputeServo(Eigen::VectorXd::Constant(1, 1000.0), zero, arm.q(), arm.qd(), dt, &servo);
  EXPECT_EQ(servo.upper[0], 0);
  EXPECT_EQ(servo.lower[0], -5);
  arm.SetJointServo(servo);
  arm.Step(dt);
  EXPECT_EQ(arm.motor_torques()[0], 0);
  EXPECT_NEAR(arm.qd()[0], 101.0, 1e-12);
  arm.SetJointState(zero, Eigen::VectorXd::Constant(1, 101.0));
  pid.ComputeServo(ref, zero, arm.q(), arm.qd(), dt, &servo);
  arm.SetJointServo(servo);
  arm.Step(dt);
  EXPECT_EQ(arm.motor_torques()[0], -5);
  EXPECT_NEAR(arm.qd()[0], 101.0 - dt * 5 / 0.01, 1e-12);
}

// The rate solve with everything at once (the lander's arm, gravity, a wrench, damping,
// friction and the PID's servo with its D term implicit, from a moving state, at dt = 2.5e-3 s):
// its conditions hold. The torques it reports, motor + dissipative, are the joint torques of
// our own Newton-Euler for qdd = (qd_new - qd_old) / dt at the start state (1e-9 relative);
// each motor torque is clamp(bias - d v, lower, upper) at the new rate v (1e-12 N m); each
// dissipative torque is -c v - f with f = friction sign(v) when v != 0 and |f| <= friction when
// v = 0 (1e-9 N m).
TEST(BulletArmTest, RateSolveMeetsItsConditions) {
  const ArmModel& m = Lander();
  const BulletArmOptions options = Options(true, true, true);
  BulletArm arm(m, options);
  JointPid pid(m, LanderGains());
  const Eigen::VectorXd pose = Pose("digging");
  Eigen::VectorXd q_ref = pose, qd_ref(6), qd(6);
  q_ref[1] += 0.004;
  q_ref[3] -= 0.02;  // saturates j_dist_pitch (2000 x 0.02 = 40 > 25.7 N m)
  qd_ref << 0.01, -0.02, 0.0, 0.05, 0.0, -0.01;
  qd << 0.002, -0.01, 0.0, 0.03, -0.001, 0.0;  // two joints at rest: friction may hold them
  const double dt = 2.5e-3;
  int stuck = 0, saturated = 0;
  arm.SetJointState(pose, qd);
  for (int k = 0; k < 40; ++k) {
    const Eigen::VectorXd q0 = arm.q(), qd0 = arm.qd();
    JointServo servo;
    pid.ComputeServo(q_ref, qd_ref, q0, qd0, dt, &servo);
    arm.SetJointServo(servo);
    Wrench w;
    w.force = Eigen::Vector3d(-20, 3, 8);
    w.point = arm.LinkPose("l_scoop_tip").translation();
    arm.ApplyWrench(6, w);
    arm.Step(dt);
    const Eigen::VectorXd v = arm.qd();
    const Eigen::VectorXd tau = arm.motor_torques() + arm.dissipative_torques();
    const Eigen::VectorXd rnea =
        InverseDynamics(m, q0, qd0, (v - qd0) / dt, options.gravity, {{6, w}});
    EXPECT_LT((tau - rnea).norm(), 1e-9 * rnea.norm()) << "step " << k;
    for (int i = 0; i < 6; ++i) {
      const double motor =
          std::clamp(servo.bias[i] - servo.gain[i] * v[i], servo.lower[i], servo.upper[i]);
      EXPECT_NEAR(arm.motor_torques()[i], motor, 1e-12) << "step " << k << " joint " << i;
      saturated += motor == servo.upper[i] || motor == servo.lower[i];
      const double f = -arm.dissipative_torques()[i] - m.joints[i].damping * v[i];
      if (v[i] != 0) {
        EXPECT_NEAR(f, std::copysign(m.joints[i].friction, v[i]), 1e-9) << k << " " << i;
      } else {
        ++stuck;
        EXPECT_LE(std::abs(f), m.joints[i].friction + 1e-9) << k << " " << i;
      }
    }
  }
  EXPECT_GT(stuck, 0);  // the test saw both kinds of joint
  EXPECT_GT(saturated, 0);
}

// The whole loop without the DEM: the lander's PID holds the digging pose (gravity 1.3 m/s^2,
// damping and friction on, dt = 5e-5 s) while an upward force on l_scoop_tip grows as 200 t N.
// The first joint whose demanded torque reaches its effort limit, at t_c, must raise
// JOINT_TORQUE_LIMIT (hold 0.1 s) at t_c + 0.1 s, within one step, and no flag of it before;
// the stop-and-hold command holds the joints where that sample had them.
TEST(ArmLoopTest, LoadRampRaisesTorqueLimitAfterTheHold) {
  const ArmModel& m = Lander();
  BulletArm arm(m, Options(true, true, true));
  const Eigen::VectorXd pose = Pose("digging");
  arm.SetJointState(pose);
  JointPid pid(m, LanderGains());
  FaultRules rules;
  rules.torque_hold_time = 0.1;
  rules.ft_joint.clear();
  FaultMonitor monitor(m, rules);
  const double dt = 5e-5;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd demanded, applied;
  ArmSample sample;
  sample.joints.resize(6);
  std::vector<double> first_cross(6, -1);
  std::vector<bool> dipped(6, false);
  Eigen::VectorXd q_at_event;
  for (int k = 0; k * dt < 1.0 && monitor.events().empty(); ++k) {
    const double t = k * dt;
    pid.Compute(pose, zero, arm.q(), arm.qd(), dt, &demanded, &applied);
    sample.time = t;
    for (int i = 0; i < 6; ++i) {
      sample.joints[i] = JointSample{arm.q()[i], arm.qd()[i], demanded[i], applied[i]};
      const bool over = std::abs(demanded[i]) >= m.joints[i].effort;
      if (over && first_cross[i] < 0) first_cross[i] = t;
      if (!over && first_cross[i] >= 0) dipped[i] = true;
    }
    monitor.Update(sample);
    if (!monitor.events().empty()) q_at_event = arm.q();
    arm.SetJointTorques(applied);
    Wrench w;
    w.force = Eigen::Vector3d(0, 0, 200 * t);
    w.point = arm.LinkPose("l_scoop_tip").translation();
    arm.ApplyWrench(6, w);
    arm.Step(dt);
  }
  ASSERT_EQ(monitor.events().size(), 1u);
  const FaultEvent& e = monitor.events()[0];
  EXPECT_EQ(e.flag, kFaultJointTorqueLimit);
  const int j = e.joint;
  for (int i = 0; i < 6; ++i) {
    if (i != j && first_cross[i] >= 0) {
      EXPECT_GE(first_cross[i], first_cross[j]) << i;
    }
  }
  EXPECT_FALSE(dipped[j]);
  EXPECT_GE(e.time, first_cross[j] + 0.1 - 1e-9);
  EXPECT_LE(e.time, first_cross[j] + 0.1 + dt + 1e-9);
  EXPECT_EQ(monitor.command().kind, Reaction::kStopAndHold);
  EXPECT_EQ(monitor.command().hold_positions, q_at_event);
  std::printf("[ info ] %s saturated at %.4f s, JOINT_TORQUE_LIMIT at %.4f s\n",
              m.joints[j].name.c_str(), first_cross[j], e.time);
}

}  // namespace
}  // namespace arm

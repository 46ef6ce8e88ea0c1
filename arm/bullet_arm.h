// The arm in Bullet: a fixed-base btMultiBody (double-precision Bullet, pkg-config
// bullet-float64) built from an ArmModel. Bullet's types stay in bullet_arm.cpp.
//
// Facts this class gets right (shared/FACTS.md section 8, tested in tests/arm/bullet_arm_test.cpp):
// - A btMultiBody link frame is the body's centre of mass turned onto its principal axes. Each
//   body's inertia is diagonalised (Eigen::SelfAdjointEigenSolver) and the transform from the
//   URDF link frame to that principal frame is kept (PrincipalFrame()); poses and twists read
//   here, and wrenches given here, go through it: callers only ever see URDF link frames.
// - Every link has a collider (a box with the body's principal moments, in the principal frame),
//   in a collision group that touches nothing: it exists for Bullet's bookkeeping only.
// - Bullet's default body damping (0.04), sleeping and 100 rad/s joint-velocity clamp are off.
// - Bullet stores URDF joint damping and friction but never applies them. They are applied
//   here, implicitly, together with the joint servos (SetJointServo: a motor torque that depends
//   on the end-of-step rate, e.g. the PID's D term): each step solves for the end-of-step joint
//   rates v with
//     M (v - v_free) = dt (-C v - f + tau_s(v)),   f_i = friction_i sign(v_i) if v_i != 0,
//                                                 |f_i| <= friction_i if v_i = 0,
//     tau_s,i(v) = clamp(bias_i - gain_i v_i, lower_i, upper_i)   (the servo's torque)
//   (v_free: the rates Bullet's articulated-body algorithm gives with every other force; M the
//   joint-space mass matrix, by the composite rigid body algorithm on Bullet's link frames and
//   inertias; C = diag(damping)). The servo's torque falls as v grows (gain >= 0), so v is the
//   minimiser of a convex function, 0.5 v'(M + dt C)v - (M v_free)'v + dt sum (friction_i |v_i| +
//   S_i(v_i)), S_i' = -tau_s,i: found by guessing which joints stick and which servos saturate,
//   solving the linear system that guess gives and correcting the guess until it is consistent (a
//   few rounds; coordinate descent, exact per joint, if that ever cycles). Stable at any step
//   (explicit damping c on a joint of inertia I diverges for dt > 2 I / c: about 2.4e-5 s on
//   j_scoop_yaw; an explicit D term d likewise for dt > 2 I / d); a joint stuck by friction stays
//   exactly still; a saturated servo gives exactly its bound.
// - The step is Bullet's articulated-body algorithm on the multibody itself (forces, then the
//   solve above, then q += dt v, btMultiBody::stepPositionsMultiDof), not
//   btMultiBodyDynamicsWorld::stepSimulation: the colliders touch nothing and there are no
//   constraints, so the world's collision detection, islands and constraint solver only cost
//   time (a few % of a step) and change nothing: with the D term explicit the rows of a
//   table-driven run equal stepSimulation's to 1e-11 % (journal section 13).
// - addLinkForce/addLinkTorque act in world axes at the link's CoM and are cleared every step:
//   ApplyWrench() converts a wrench about any world point, for the next Step() only. Gravity is
//   applied the same way (Bullet's world gravity is zero), so the arm's forces are all here.
//
// Integration: semi-implicit Euler, v_new from the solve above (v_free + dt qdd(q, v, forces)
// with no servo, damping or friction); q += dt * v_new. Step() never throws.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "arm/arm_model.h"
#include "arm/kinematics.h"

namespace arm {

// Velocity of a frame: `linear` of its origin, `angular` of the body; world axes [m/s, rad/s].
struct Twist {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
};

// A motor torque per joint that depends on the joint's end-of-step rate v [rad/s]:
//   tau_i = clamp(bias_i - gain_i v_i, lower_i, upper_i)   [N m]
// (a PID's output with its D term taken at the step's end: arm/controller.h). Each of size dof.
struct JointServo {
  Eigen::VectorXd bias;   // [N m]
  Eigen::VectorXd gain;   // >= 0 [N m s/rad]
  Eigen::VectorXd lower;  // [N m]
  Eigen::VectorXd upper;  // >= lower [N m]
  void Resize(int n);     // bias and gain 0, bounds -inf and +inf
};

struct BulletArmOptions {
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -1.3);        // [m/s^2], world axes
  Eigen::Isometry3d base_pose = Eigen::Isometry3d::Identity();  // base link frame in the world
  bool joint_damping = true;                                    // apply the URDF's joint damping
  bool joint_friction = true;                                   // apply the URDF's Coulomb friction
};

class BulletArm {
 public:
  explicit BulletArm(const ArmModel& model, const BulletArmOptions& options = {});
  ~BulletArm();
  BulletArm(const BulletArm&) = delete;
  BulletArm& operator=(const BulletArm&) = delete;

  const ArmModel& model() const { return model_; }
  int dof() const { return model_.dof(); }
  double time() const { return time_; }  // simulated time since creation [s]

  void SetGravity(const Eigen::Vector3d& gravity);
  const Eigen::Vector3d& gravity() const { return gravity_; }

  // Joint positions [rad] and rates [rad/s]; sets both at once (rates zero if omitted).
  void SetJointState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
  void SetJointState(const Eigen::VectorXd& q);
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }

  // Motor torques for the next Step() only [N m] (applied exactly, addJointTorque): the servo
  // of every joint set to bias tau, gain 0, no bounds.
  void SetJointTorques(const Eigen::VectorXd& tau);
  // The joint servos for the next Step() only (bullet_arm.h's solve): joint i's motor torque is
  // clamp(bias_i - gain_i v_i, lower_i, upper_i) at the end-of-step rate v_i [N m, N m s/rad];
  // gain >= 0, lower <= upper (asserted).
  void SetJointServo(const JointServo& servo);
  // Adds a wrench on `body` for the next Step() only: force and torque in world axes, the torque
  // about the world point `wrench.point` [N, N m, m].
  void ApplyWrench(int body, const Wrench& wrench);

  // Advances by dt [s]. Clears the torques and wrenches given for it.
  void Step(double dt);

  // After the last Step(): (qd_new - qd_old) / dt [rad/s^2], the motor (servo) torques applied,
  // and the joint damping + friction torques applied [N m].
  const Eigen::VectorXd& qdd() const { return qdd_; }
  const Eigen::VectorXd& motor_torques() const { return last_motor_; }
  const Eigen::VectorXd& dissipative_torques() const { return last_dissipative_; }

  // World pose of a body's URDF link frame (read from Bullet's link frame through
  // PrincipalFrame()), and of any URDF link of the model.
  Eigen::Isometry3d BodyPose(int body) const;
  Eigen::Isometry3d LinkPose(const std::string& link) const;
  // Velocity of the body's URDF link frame origin (or of a link's), world axes.
  Twist BodyTwist(int body) const;
  Twist LinkTwist(const std::string& link) const;
  // Bullet's own link frame: the body's CoM on its principal axes, in the world.
  Eigen::Isometry3d BulletLinkFrame(int body) const;
  // The stored transform: that principal frame in the body's URDF link frame.
  const Eigen::Isometry3d& PrincipalFrame(int body) const { return principal_[body]; }
  // Diagonal inertia Bullet was given (the principal moments) [kg m^2].
  const Eigen::Vector3d& PrincipalMoments(int body) const { return moments_[body]; }

 private:
  struct Impl;
  void Refresh();              // reads q, qd and the link frames back from Bullet
  void MassMatrix();           // M(q) into the solve's scratch
  void SolveRates(double dt);  // v_free -> v (bullet_arm.h's solve), motor and dissipative torques

  ArmModel model_;
  Eigen::Vector3d gravity_;
  BulletArmOptions options_;
  std::vector<Eigen::Isometry3d> principal_;  // per body: principal frame in the URDF link frame
  std::vector<Eigen::Vector3d> moments_;      // per body: principal moments
  JointServo servo_;                          // for the next Step()
  Eigen::VectorXd q_, qd_, qdd_, last_motor_, last_dissipative_;
  double time_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace arm

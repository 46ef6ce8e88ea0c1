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
//   here, implicitly: each step solves for the end-of-step joint rates v with
//     M (v - v_free) = dt (-C v + f),   |f_i| <= friction_i, f_i = -friction_i sign(v_i) if v_i !=
//     0
//   (v_free: the rates Bullet would reach without them; M the joint-space mass matrix, from
//   Bullet's own articulated-body algorithm; C = diag(damping)), the minimiser of the convex
//   0.5 v'(M + dt C)v - (M v_free)'v + dt sum friction_i |v_i|, then adds the equivalent joint
//   torque M (v - v_free) / dt. Stable at any step (explicit damping c on a joint of inertia I
//   diverges for dt > 2 I / c: about 2.4e-5 s on j_scoop_yaw); a joint stuck by friction stays
//   exactly still.
// - addLinkForce/addLinkTorque act in world axes at the link's CoM and are cleared every step:
//   ApplyWrench() converts a wrench about any world point, for the next Step() only. Gravity is
//   applied the same way (Bullet's world gravity is zero), so the arm's forces are all here.
//
// Integration: Bullet's semi-implicit Euler, v += dt * qdd(q, v, forces); q += dt * v.
// Step() never throws.
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

  // Motor torques for the next Step() only [N m] (applied exactly, addJointTorque).
  void SetJointTorques(const Eigen::VectorXd& tau);
  // Adds a wrench on `body` for the next Step() only: force and torque in world axes, the torque
  // about the world point `wrench.point` [N, N m, m].
  void ApplyWrench(int body, const Wrench& wrench);

  // Advances by dt [s]. Clears the torques and wrenches given for it.
  void Step(double dt);

  // After the last Step(): (qd_new - qd_old) / dt [rad/s^2], the motor torques applied, and the
  // joint damping + friction torques applied [N m].
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
  void Refresh();  // reads q, qd and the link frames back from Bullet
  void SolveDissipation(double dt);

  ArmModel model_;
  Eigen::Vector3d gravity_;
  BulletArmOptions options_;
  std::vector<Eigen::Isometry3d> principal_;  // per body: principal frame in the URDF link frame
  std::vector<Eigen::Vector3d> moments_;      // per body: principal moments
  Eigen::VectorXd q_, qd_, qdd_, tau_, last_motor_, last_dissipative_;
  double time_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace arm

// The arm's own maths in Eigen, independent of Bullet: forward kinematics, the Jacobian of a
// point of a body, and inverse dynamics by the recursive Newton-Euler algorithm (Featherstone,
// Rigid Body Dynamics Algorithms, 2008, section 5.3; here in world axes, about each body's CoM).
// Used by the controller's IK, by `scoopsim arm info`, by the force/torque sensor, and by the tests
// as the oracle for Bullet.
//
// Frames: "world" is the base body's frame placed at `base` (identity: the URDF root link's
// frame). Joint angles q [rad], rates qd [rad/s], accelerations qdd [rad/s^2], size dof().
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "arm/arm_model.h"

namespace arm {

using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// A force and a torque in world axes; the torque is about `point` (world) [N, N m, m].
struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

// An external wrench on a body (for inverse dynamics).
struct BodyWrench {
  int body = 0;
  Wrench wrench;
};

// World poses of all bodies' frames (bodies.size() entries).
std::vector<Eigen::Isometry3d> BodyPoses(
    const ArmModel& model, const Eigen::VectorXd& q,
    const Eigen::Isometry3d& base = Eigen::Isometry3d::Identity());

// World pose of a URDF link's frame (throws std::invalid_argument for an unknown link).
Eigen::Isometry3d LinkPose(const ArmModel& model, const Eigen::VectorXd& q, const std::string& link,
                           const Eigen::Isometry3d& base = Eigen::Isometry3d::Identity());

// Geometric Jacobian of a point fixed to `body` at world position `point` (at q): rows 0-2 the
// point's velocity, rows 3-5 the body's angular velocity, world axes; 6 x dof().
// A wrench W = (F at the point, T) on the body needs joint torques -J^T W to be held.
Matrix6Xd PointJacobian(const ArmModel& model, const Eigen::VectorXd& q, int body,
                        const Eigen::Vector3d& point,
                        const Eigen::Isometry3d& base = Eigen::Isometry3d::Identity());

// Inverse dynamics: the joint torques tau with M(q) qdd + c(q, qd) = tau + (gravity and
// `external` mapped to the joints). `gravity` in world axes [m/s^2].
// If `joint_wrenches` is given, it receives for each joint i the wrench the parent body exerts
// on the subtree beyond joint i, world axes, torque about the joint's origin (the wrench a
// force/torque sensor in joint i carries).
Eigen::VectorXd InverseDynamics(const ArmModel& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                                const Eigen::Vector3d& gravity,
                                const std::vector<BodyWrench>& external = {},
                                std::vector<Wrench>* joint_wrenches = nullptr,
                                const Eigen::Isometry3d& base = Eigen::Isometry3d::Identity());

// The torques that hold the arm still at q against gravity alone.
Eigen::VectorXd GravityTorques(const ArmModel& model, const Eigen::VectorXd& q,
                               const Eigen::Vector3d& gravity);

}  // namespace arm

#include "arm/kinematics.h"

#include <cassert>
#include <stdexcept>

namespace arm {

std::vector<Eigen::Isometry3d> BodyPoses(const ArmModel& model, const Eigen::VectorXd& q,
                                         const Eigen::Isometry3d& base) {
  assert(q.size() == model.dof());
  std::vector<Eigen::Isometry3d> poses(model.bodies.size());
  poses[0] = base;
  for (int i = 0; i < model.dof(); ++i) {
    const Joint& j = model.joints[i];
    poses[i + 1] = poses[i] * j.origin * Eigen::AngleAxisd(q[i], j.axis);
  }
  return poses;
}

Eigen::Isometry3d LinkPose(const ArmModel& model, const Eigen::VectorXd& q, const std::string& link,
                           const Eigen::Isometry3d& base) {
  int body = 0;
  Eigen::Isometry3d in_body;
  if (!model.FindLink(link, &body, &in_body)) {
    throw std::invalid_argument("arm: no link named '" + link + "'");
  }
  return BodyPoses(model, q, base)[body] * in_body;
}

Matrix6Xd PointJacobian(const ArmModel& model, const Eigen::VectorXd& q, int body,
                        const Eigen::Vector3d& point, const Eigen::Isometry3d& base) {
  const std::vector<Eigen::Isometry3d> poses = BodyPoses(model, q, base);
  Matrix6Xd jac = Matrix6Xd::Zero(6, model.dof());
  // Serial chain: joints 0 .. body-1 move the body.
  for (int i = 0; i < body; ++i) {
    const Eigen::Vector3d axis = poses[i + 1].linear() * model.joints[i].axis;
    const Eigen::Vector3d origin = poses[i + 1].translation();
    jac.block<3, 1>(0, i) = axis.cross(point - origin);
    jac.block<3, 1>(3, i) = axis;
  }
  return jac;
}

Eigen::VectorXd InverseDynamics(const ArmModel& model, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                                const Eigen::Vector3d& gravity,
                                const std::vector<BodyWrench>& external,
                                std::vector<Wrench>* joint_wrenches,
                                const Eigen::Isometry3d& base) {
  const int n = model.dof();
  const std::vector<Eigen::Isometry3d> poses = BodyPoses(model, q, base);
  // Forward pass: angular velocity w, angular acceleration dw, CoM acceleration a (world axes).
  std::vector<Eigen::Vector3d> w(n + 1, Eigen::Vector3d::Zero()),
      dw(n + 1, Eigen::Vector3d::Zero()), a(n + 1, Eigen::Vector3d::Zero()), com(n + 1),
      axis(n + 1), origin(n + 1);
  com[0] = poses[0] * model.bodies[0].inertial.com;
  for (int i = 1; i <= n; ++i) {
    const int p = i - 1;
    axis[i] = poses[i].linear() * model.joints[i - 1].axis;
    origin[i] = poses[i].translation();
    com[i] = poses[i] * model.bodies[i].inertial.com;
    w[i] = w[p] + axis[i] * qd[i - 1];
    dw[i] = dw[p] + axis[i] * qdd[i - 1] + w[p].cross(axis[i] * qd[i - 1]);
    // Acceleration of the joint origin as a point of the parent, then of this body's CoM.
    const Eigen::Vector3d rp = origin[i] - com[p];
    const Eigen::Vector3d a_origin = a[p] + dw[p].cross(rp) + w[p].cross(w[p].cross(rp));
    const Eigen::Vector3d r = com[i] - origin[i];
    a[i] = a_origin + dw[i].cross(r) + w[i].cross(w[i].cross(r));
  }
  // Net force F and torque N (about the CoM) each body needs, less gravity and external loads.
  std::vector<Eigen::Vector3d> f(n + 1), t(n + 1);
  for (int i = 1; i <= n; ++i) {
    const Inertial& in = model.bodies[i].inertial;
    const Eigen::Matrix3d iw = poses[i].linear() * in.inertia * poses[i].linear().transpose();
    f[i] = in.mass * (a[i] - gravity);
    t[i] = iw * dw[i] + w[i].cross(iw * w[i]);
  }
  for (const BodyWrench& e : external) {
    if (e.body < 1 || e.body > n) continue;  // the base carries its own loads
    f[e.body] -= e.wrench.force;
    t[e.body] -= e.wrench.torque + (e.wrench.point - com[e.body]).cross(e.wrench.force);
  }
  // Backward pass: the wrench across joint i (parent on subtree), torque about origin[i].
  Eigen::VectorXd tau(n);
  Eigen::Vector3d f_child = Eigen::Vector3d::Zero(), n_child = Eigen::Vector3d::Zero();
  Eigen::Vector3d child_origin = Eigen::Vector3d::Zero();
  if (joint_wrenches) joint_wrenches->assign(n, Wrench{});
  for (int i = n; i >= 1; --i) {
    const Eigen::Vector3d fi = f[i] + f_child;
    const Eigen::Vector3d ni = t[i] + (com[i] - origin[i]).cross(f[i]) + n_child +
                               (child_origin - origin[i]).cross(f_child);
    tau[i - 1] = axis[i].dot(ni);
    if (joint_wrenches) (*joint_wrenches)[i - 1] = Wrench{fi, ni, origin[i]};
    f_child = fi;
    n_child = ni;
    child_origin = origin[i];
  }
  return tau;
}

Eigen::VectorXd GravityTorques(const ArmModel& model, const Eigen::VectorXd& q,
                               const Eigen::Vector3d& gravity) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.dof());
  return InverseDynamics(model, q, zero, zero, gravity);
}

}  // namespace arm

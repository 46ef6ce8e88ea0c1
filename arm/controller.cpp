#include "arm/controller.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "arm/kinematics.h"

namespace arm {

std::vector<PidGains> LanderGains() { return {kLanderGains.begin(), kLanderGains.end()}; }

double LimitTorque(double demanded, double velocity, const Joint& joint) {
  double applied = std::clamp(demanded, -joint.effort, joint.effort);
  if (velocity > joint.velocity && applied > 0) applied = 0;
  if (velocity < -joint.velocity && applied < 0) applied = 0;
  return applied;
}

JointPid::JointPid(const ArmModel& model, std::vector<PidGains> gains)
    : joints_(model.joints), gains_(std::move(gains)) {
  if (static_cast<int>(gains_.size()) != model.dof()) {
    throw std::invalid_argument("JointPid: " + std::to_string(gains_.size()) +
                                " gains for an arm of " + std::to_string(model.dof()) + " joints");
  }
  integral_ = Eigen::VectorXd::Zero(model.dof());
}

void JointPid::Reset() { integral_.setZero(); }

void JointPid::Preload(const Eigen::VectorXd& torques) {
  for (int i = 0; i < static_cast<int>(joints_.size()); ++i) {
    const PidGains& g = gains_[i];
    integral_[i] =
        g.i > 0 ? std::clamp(torques[i], -joints_[i].effort, joints_[i].effort) / g.i : 0.0;
  }
}

void JointPid::Integrate(int i, double e, double dt) {
  const PidGains& g = gains_[i];
  integral_[i] += e * dt;
  if (g.i > 0) {
    const double bound = joints_[i].effort / g.i;  // anti-windup: |i * integral| <= effort
    integral_[i] = std::clamp(integral_[i], -bound, bound);
  }
}

void JointPid::Compute(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
                       const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double dt,
                       Eigen::VectorXd* demanded, Eigen::VectorXd* applied) {
  const int n = static_cast<int>(joints_.size());
  demanded->resize(n);
  applied->resize(n);
  for (int i = 0; i < n; ++i) {
    const PidGains& g = gains_[i];
    const double e = q_ref[i] - q[i];
    const double de = qd_ref[i] - qd[i];
    Integrate(i, e, dt);
    (*demanded)[i] = g.p * e + g.i * integral_[i] + g.d * de;
    (*applied)[i] = LimitTorque((*demanded)[i], qd[i], joints_[i]);
  }
}

void JointPid::ComputeServo(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
                            const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double dt,
                            JointServo* servo) {
  const int n = static_cast<int>(joints_.size());
  if (servo->bias.size() != n) servo->Resize(n);
  for (int i = 0; i < n; ++i) {
    const PidGains& g = gains_[i];
    const Joint& j = joints_[i];
    Integrate(i, q_ref[i] - q[i], dt);
    servo->bias[i] = g.p * (q_ref[i] - q[i]) + g.i * integral_[i] + g.d * qd_ref[i];
    servo->gain[i] = g.d;
    // LimitTorque's rule as bounds: no torque toward an exceeded velocity limit.
    servo->lower[i] = qd[i] < -j.velocity ? 0.0 : -j.effort;
    servo->upper[i] = qd[i] > j.velocity ? 0.0 : j.effort;
  }
}

void JointPid::Demanded(const JointServo& servo, const Eigen::VectorXd& v,
                        Eigen::VectorXd* demanded) {
  *demanded = servo.bias - servo.gain.cwiseProduct(v);
}

namespace {

// Pose error (position, orientation as a rotation vector), base frame.
void PoseError(const Eigen::Isometry3d& target, const Eigen::Isometry3d& now, Eigen::Vector3d* dp,
               Eigen::Vector3d* dr) {
  *dp = target.translation() - now.translation();
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(target.linear() * now.linear().transpose()));
  *dr = aa.angle() * aa.axis();
}

void ClampToLimits(const ArmModel& model, Eigen::VectorXd* q) {
  for (int i = 0; i < model.dof(); ++i) {
    const Joint& j = model.joints[i];
    if (j.has_position_limits) (*q)[i] = std::clamp((*q)[i], j.lower, j.upper);
  }
}

}  // namespace

IkResult SolveIk(const ArmModel& model, const std::string& link, const Eigen::Isometry3d& target,
                 const Eigen::VectorXd& q_start, const IkOptions& options) {
  int body = 0;
  Eigen::Isometry3d in_body;
  if (!model.FindLink(link, &body, &in_body)) {
    throw std::invalid_argument("SolveIk: no link named '" + link + "'");
  }
  const double w = options.orientation_weight;
  IkResult result;
  result.q = q_start;
  ClampToLimits(model, &result.q);
  Eigen::Vector3d dp, dr;
  for (int it = 0;; ++it) {
    const Eigen::Isometry3d now = BodyPoses(model, result.q)[body] * in_body;
    PoseError(target, now, &dp, &dr);
    result.position_error = dp.norm();
    result.angle_error = dr.norm();
    result.iterations = it;
    if (result.position_error <= options.position_tolerance &&
        result.angle_error <= options.angle_tolerance) {
      result.converged = true;
      break;
    }
    if (it == options.max_iterations) break;
    Matrix6Xd jac = PointJacobian(model, result.q, body, now.translation());
    jac.bottomRows<3>() *= w;
    Eigen::Matrix<double, 6, 1> e;
    e << dp, w * dr;
    const Eigen::Matrix<double, 6, 6> a =
        jac * jac.transpose() +
        options.damping * options.damping * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::VectorXd dq = jac.transpose() * a.ldlt().solve(e);
    const double largest = dq.cwiseAbs().maxCoeff();
    if (largest > options.max_step) dq *= options.max_step / largest;
    result.q += dq;
    ClampToLimits(model, &result.q);
  }
  return result;
}

JointPath FollowPosePath(const ArmModel& model, const std::string& link,
                         const std::vector<PosePoint>& path, const Eigen::VectorXd& q_start,
                         const IkOptions& options) {
  const int n = model.dof();
  JointPath out;
  Eigen::VectorXd q = q_start;
  ClampToLimits(model, &q);
  for (size_t k = 0; k < path.size(); ++k) {
    const IkResult ik = SolveIk(model, link, path[k].pose, q, options);
    Eigen::VectorXd step = ik.q - q;
    if (k > 0) {
      const double dt = path[k].time - path[k - 1].time;
      double scale = 1;
      for (int i = 0; i < n; ++i) {
        const double allowed = model.joints[i].velocity * dt;
        if (std::abs(step[i]) > allowed) scale = std::min(scale, allowed / std::abs(step[i]));
      }
      if (scale < 1) {
        ++out.velocity_limited;
        step *= scale;
      }
    } else {
      step.setZero();
      q = ik.q;  // the first sample is where the path starts, not a move
    }
    Eigen::VectorXd next = q + step;
    ClampToLimits(model, &next);
    const double dt = k > 0 ? path[k].time - path[k - 1].time : 0;
    out.time.push_back(path[k].time);
    out.qd.push_back(k > 0 && dt > 0 ? Eigen::VectorXd((next - q) / dt)
                                     : Eigen::VectorXd(Eigen::VectorXd::Zero(n)));
    q = next;
    out.q.push_back(q);
    Eigen::Vector3d dp, dr;
    PoseError(path[k].pose, LinkPose(model, q, link), &dp, &dr);
    out.position_error.push_back(dp.norm());
    out.angle_error.push_back(dr.norm());
    out.max_position_error = std::max(out.max_position_error, dp.norm());
    out.max_angle_error = std::max(out.max_angle_error, dr.norm());
  }
  return out;
}

}  // namespace arm

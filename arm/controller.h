// Joint control and inverse kinematics of the arm.
//
// JointPid: the lander's controller, a PID per joint on the position error whose output is
// clamped at the joint's effort limit: the clamp is the motor's torque saturation. Each step
// gives the demanded torque (the PID's output) and the applied one, to be applied exactly
// (BulletArm::SetJointTorques, i.e. addJointTorque) and logged; never a btMultiBodyJointMotor,
// a velocity constraint that fights it. The rule from demanded to applied (LimitTorque):
//   applied = clamp(demanded, -effort, +effort)
//   if velocity >  velocity_limit and applied > 0: applied = 0
//   if velocity < -velocity_limit and applied < 0: applied = 0
// the second and third lines as Gazebo's Joint::CheckAndTruncateForce: no torque in the
// direction of an exceeded velocity limit. The PID (ros_control's form):
//   e = q_ref - q, de = qd_ref - qd, integral += e dt (clamped so |i integral| <= effort),
//   demanded = p e + i integral + d de.
// No angle wrapping: continuous joints are driven through any number of turns.
// The D term, two ways (PidDTerm):
// - explicit (Compute): qd is the measured rate at the step's start; stable for dt < 2 I / d, I
//   the joint's effective inertia (about 1.2e-4 s for j_scoop_yaw, d = 10).
// - implicit (ComputeServo, the default of the table-driven arm): the D term is taken at the
//   step's end rate v, solved with the joint dynamics (arm::BulletArm's servo, bullet_arm.h):
//     demanded(v) = bias - d v,   bias = p e + i integral + d qd_ref,
//     applied = clamp(demanded(v), lower, upper),
//   lower, upper = -+effort, with the velocity rule above as a bound: upper = 0 when
//   qd > velocity_limit, lower = 0 when qd < -velocity_limit (qd measured at the step's start).
//   Backward Euler in the D term: stable at any step, so the arm can step at the lander's own
//   400 Hz; the P and I terms stay explicit (semi-implicit Euler: stable for dt < 2 / omega,
//   omega = sqrt(p / I): 2.5 ms is several times inside that on every joint of the lander's arm).
//   The demanded and applied torques are known after the step (Demanded()).
//
// Inverse kinematics: damped least squares on the Jacobian of a link frame (SolveIk), and a
// Cartesian pose path of that link turned into joint references that respect joint position
// limits and velocity limits (FollowPosePath).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "arm/arm_model.h"
#include "arm/bullet_arm.h"

namespace arm {

// Where the PID's D term takes the joint rate: at the step's start (explicit) or its end
// (implicit, solved with the dynamics).
enum class PidDTerm { kExplicit, kImplicit };

struct PidGains {
  double p = 0;  // [N m/rad]
  double i = 0;  // [N m/(rad s)]
  double d = 0;  // [N m s/rad]
};

// The lander's gains, joint order 1..6 (shared/FACTS.md section 2).
constexpr std::array<PidGains, 6> kLanderGains = {{{8300, 10, 300},
                                                   {20000, 0.2, 150},
                                                   {11000, 2, 100},
                                                   {2000, 0.06, 20},
                                                   {1000, 0.01, 60},
                                                   {100, 0.01, 10}}};
std::vector<PidGains> LanderGains();

// The saturation rule above, for one joint.
double LimitTorque(double demanded, double velocity, const Joint& joint);

class JointPid {
 public:
  // gains.size() == model.dof() (throws std::invalid_argument otherwise).
  JointPid(const ArmModel& model, std::vector<PidGains> gains);
  void Reset();  // integral terms to zero
  // Sets the integral terms so that they alone give `torques` [N m] (e.g. the gravity torques of
  // an arm that was holding itself up before the controller took over), within the anti-windup
  // bound; joints with i = 0 keep zero.
  void Preload(const Eigen::VectorXd& torques);
  // One control step of dt [s]: references and measured state in, demanded and applied torques
  // out (all of size dof()).
  void Compute(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
               const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double dt,
               Eigen::VectorXd* demanded, Eigen::VectorXd* applied);
  // The implicit form: the same integral update, the servo of the step in *servo (bias, gain d,
  // bounds as above) for BulletArm::SetJointServo.
  void ComputeServo(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref,
                    const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double dt,
                    JointServo* servo);
  // After the step: the demanded torque of a servo at the end-of-step rates v (bias - d v).
  static void Demanded(const JointServo& servo, const Eigen::VectorXd& v,
                       Eigen::VectorXd* demanded);
  const std::vector<PidGains>& gains() const { return gains_; }

 private:
  std::vector<Joint> joints_;
  std::vector<PidGains> gains_;
  Eigen::VectorXd integral_;
  void Integrate(int i, double e, double dt);  // integral += e dt, anti-windup clamp
};

struct IkOptions {
  double damping = 1e-2;            // lambda of damped least squares [m]
  double orientation_weight = 0.1;  // metres per radian: how orientation error counts [m/rad]
  int max_iterations = 200;
  double position_tolerance = 1e-6;  // [m]
  double angle_tolerance = 1e-5;     // [rad]
  double max_step = 0.1;             // largest joint change per iteration [rad]
};

struct IkResult {
  Eigen::VectorXd q;
  double position_error = 0;  // |p - p_target| [m]
  double angle_error = 0;     // angle of R_target R^T [rad]
  int iterations = 0;
  bool converged = false;
};

// The joint angles that put `link`'s frame at `target` (base frame), from q_start: iterates
//   dq = J^T (J J^T + lambda^2 I)^-1 e,   e = (p_target - p, w (orientation error as axis-angle))
// with the rows of J for orientation scaled by w = orientation_weight, each dq scaled down to
// max_step, and joints with position limits clamped into [lower, upper] after each iteration.
IkResult SolveIk(const ArmModel& model, const std::string& link, const Eigen::Isometry3d& target,
                 const Eigen::VectorXd& q_start, const IkOptions& options = {});

struct PosePoint {
  double time = 0;                                         // [s]
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // link frame in the base frame
};

struct JointPath {
  std::vector<double> time;            // [s], the path's times
  std::vector<Eigen::VectorXd> q;      // joint references [rad]
  std::vector<Eigen::VectorXd> qd;     // (q_k - q_{k-1}) / (t_k - t_{k-1}), zero at k = 0
  std::vector<double> position_error;  // achieved vs asked, per sample [m]
  std::vector<double> angle_error;     // [rad]
  int velocity_limited = 0;            // samples where a velocity limit held the step back
  double max_position_error = 0;
  double max_angle_error = 0;
};

// Joint references for a pose path of `link`: at each sample, IK from the previous sample's
// joints; then the step is scaled down uniformly so that |dq_i| <= velocity_i (t_k - t_{k-1})
// for every joint, and revolute joints are clamped to their limits. The error columns say how
// far the references fall from the path (e.g. when it asks for more than the velocity limits).
JointPath FollowPosePath(const ArmModel& model, const std::string& link,
                         const std::vector<PosePoint>& path, const Eigen::VectorXd& q_start,
                         const IkOptions& options = {});

}  // namespace arm

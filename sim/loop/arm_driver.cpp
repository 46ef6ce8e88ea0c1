#include "sim/loop/arm_driver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "arm/arm_model.h"
#include "arm/bullet_arm.h"
#include "arm/controller.h"
#include "arm/fault_monitor.h"
#include "arm/kinematics.h"
#include "dem/triangle.h"
#include "sim/files/arm_geometry.h"
#include "sim/files/h5_output.h"
#include "sim/loop/progress.h"

namespace sim {
namespace {

constexpr double kSample = 0.01;        // path sampling for the IK [s]
constexpr int kMaxSamples = 100000000;  // of a path (a pass of 1e6 s), kept within int's range

Eigen::Vector3d ToEigen(const dem::Vec3& v) { return {v.x, v.y, v.z}; }
dem::Vec3 ToDem(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

Eigen::Isometry3d ToEigen(const dem::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
          .normalized()
          .toRotationMatrix();
  t.translation() = ToEigen(p.position);
  return t;
}

dem::Quat ToDem(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

arm::Reaction ToArm(ArmReaction r) {
  switch (r) {
    case ArmReaction::kContinue:
      return arm::Reaction::kContinue;
    case ArmReaction::kRetract:
      return arm::Reaction::kRetract;
    case ArmReaction::kStop:
    default:
      return arm::Reaction::kStopAndHold;
  }
}

// Joint references sampled in time (linear in between).
struct JointPlan {
  std::vector<double> t;           // [s] pass time, increasing
  std::vector<Eigen::VectorXd> q;  // [rad]
  double duration = 0;             // [s]
  double scale = 1;                // time scale applied to the tool path
  double ik_error = 0;             // largest IK position error [m]
};

}  // namespace

// Farther out of reach than this the scoop cannot follow the dig at all: bad input, not a run.
constexpr double kReachTolerance = 0.05;  // [m] of IK position error

struct ArmDriver::Impl {
  std::string scene_path;
  bool announce = true;  // the plan's notes on stderr (slowed, out of reach)
  ArmSpec spec;
  std::vector<ObstacleSpec> obstacles;
  dem::Vec3 gravity;
  double dt = 0;  // DEM step [s]
  int k = 1;      // DEM steps per Bullet step
  arm::ArmModel model;
  ArmGeometry geometry;  // the links, for frames and snapshots
  int n = 0;
  int scoop_body = 0;
  int sensor = -1;  // sensor joint index
  KinematicDriver path;
  DigSpec dig;
  bool start_buried = false;
  const dem::TriangleMesh* mesh = nullptr;  // the scoop, l_scoop coordinates

  // Set at the first plan (the auto base needs the bed's surface).
  bool base_set = false;
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  std::unique_ptr<arm::BulletArm> bullet;
  std::unique_ptr<arm::JointPid> pid;
  std::unique_ptr<arm::FaultMonitor> monitor;
  std::map<int, JointPlan> plans;  // per pass

  // The current pass.
  const JointPlan* plan = nullptr;
  size_t seg = 0;  // plan segment of the last reference
  enum class Mode { kFollow, kHold, kRetract } mode = Mode::kFollow;
  Eigen::VectorXd hold_q;
  JointPlan retract;
  double end_tau = 0;         // the pass ends here [s]
  double t_b = 0;             // pass time of Bullet's state [s]
  dem::MeshMotion cur, prev;  // scoop motion at t_b and t_b - h
  dem::Vec3 sent_origin;      // mesh origin of the last MotionAt
  dem::Vec3 f_sum, t_sum;     // DEM wrench since the last Bullet step (torque about world 0)
  int count = 0;
  arm::Wrench dem_wrench, contact_wrench;  // applied in the last Bullet step
  Eigen::VectorXd q_ref, qd_ref, demanded, applied;
  bool external_ref = false;   // SetJointReference: follow external_q, not the path
  Eigen::VectorXd external_q;  // [rad] (n)
  arm::JointServo servo;  // the PID's step with its D term implicit (arm.d_term: implicit)
  arm::ArmSample sample;
  uint64_t active = 0;             // fault conditions true at the last step
  arm::RowFaultBits active_since;  // OR of `active` over the steps since the last /arm/ row
  double next_ft = 0;
  Eigen::Vector3d ft_force = Eigen::Vector3d::Zero(), ft_torque = Eigen::Vector3d::Zero();
  double tracking = 0;  // last tracking error [m]
  double start_time = 0, pass_offset = 0, last_tau = 0;
  int pass = 0;
  bool attributes_written = false;

  ArmReport report;
  double track_sum2 = 0;
  int64_t track_n = 0;

  Impl(const Scene& scene)
      : scene_path(scene.path),
        spec(scene.arm),
        obstacles(scene.obstacles),
        gravity(scene.gravity),
        dt(scene.time_step),
        k(scene.arm.substeps),
        model(arm::Derated(*scene.arm.model, scene.arm.derate)),
        geometry(scene.arm.model),
        path(scene.dig.trajectory, scene.dig.heading, scene.dig.bite_depth, scene.dig.start_buried),
        dig(scene.dig),
        start_buried(scene.dig.start_buried) {
    n = model.dof();
    scoop_body = n;  // the tip body: l_scoop's frame (arm/arm_model.h)
    sensor = spec.sensor_joint.empty() ? -1 : model.JointIndex(spec.sensor_joint);
    q_ref = qd_ref = demanded = applied = Eigen::VectorXd::Zero(n);
    servo.Resize(n);
    sample.joints.resize(n);
    report.peak_demanded.assign(n, 0.0);
    report.saturation_time.assign(n, 0.0);
    report.first_saturation.assign(n, std::numeric_limits<double>::quiet_NaN());
    for (int i = 0; i < n; ++i) {
      report.joints.push_back(model.joints[i].name);
      report.effort_limit.push_back(model.joints[i].effort);
      report.urdf_effort_limit.push_back(scene.arm.model->joints[i].effort);
      report.effort_derate.push_back(
          i < static_cast<int>(scene.arm.derate.size()) ? scene.arm.derate[i] : 1.0);
    }
  }

  double Time(double tau) const { return start_time + pass_offset + tau; }

  // base_link in the world: given, or under the path's start at the bed's surface.
  void PlaceBase(const DigSpec& dig, const BedContext& bed) {
    if (base_set) return;
    double yaw = spec.base_yaw;
    Eigen::Vector3d position = ToEigen(spec.base_position);
    if (!spec.base_given) {
      yaw = dig.heading;
      const Eigen::Vector3d under(dig.trajectory.pivot_start.x, dig.trajectory.pivot_start.y,
                                  bed.surface);
      position = under - Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::Vector3d(spec.reach_x, spec.reach_y, -spec.base_height);
    }
    base = Eigen::Isometry3d::Identity();
    base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    base.translation() = position;
    report.base = {position.x(), position.y(), position.z(), yaw};
    base_set = true;
  }

  // The pass's tool path as joint references, time-scaled to the joint velocity limits.
  const JointPlan& Plan(int pass, const BedContext& bed, const DigSpec& dig) {
    const auto found = plans.find(pass);
    if (found != plans.end()) return found->second;
    PlaceBase(dig, bed);
    const PassStart start = path.BeginPass(pass, bed);
    const double d = start.duration;
    std::vector<arm::PosePoint> points;
    // In double first: a cast of a count past int's range is undefined behaviour.
    const int samples =
        static_cast<int>(std::clamp(std::ceil(d / kSample - 1e-9), 1.0, double{kMaxSamples}));
    const Eigen::Isometry3d to_base = base.inverse();
    for (int s = 0; s <= samples; ++s) {
      const double tau = std::min(d, s * kSample);
      points.push_back({tau, to_base * ToEigen(path.MotionAt(tau).pose)});
    }
    // IK with the velocity limits lifted: the path's own rates, then the scale that brings them
    // under the limits.
    arm::ArmModel free = model;
    for (arm::Joint& j : free.joints) j.velocity = std::numeric_limits<double>::max();
    Eigen::VectorXd seed(n);
    for (int i = 0; i < n; ++i) seed[i] = spec.initial[i];
    const arm::JointPath jp = arm::FollowPosePath(free, model.tip_link, points, seed);
    JointPlan p;
    for (size_t s = 1; s < jp.q.size(); ++s) {
      const double h = jp.time[s] - jp.time[s - 1];
      if (!(h > 0)) continue;
      for (int i = 0; i < n; ++i) {
        const double rate = std::abs(jp.q[s][i] - jp.q[s - 1][i]) / h;
        p.scale = std::max(p.scale, rate / (spec.velocity_margin * model.joints[i].velocity));
      }
    }
    for (size_t s = 0; s < jp.q.size(); ++s) {
      if (s > 0 && !(jp.time[s] > jp.time[s - 1])) continue;
      p.t.push_back(p.scale * jp.time[s]);
      p.q.push_back(jp.q[s]);
    }
    p.duration = p.scale * d;
    p.ik_error = jp.max_position_error;
    report.time_scale = std::max(report.time_scale, p.scale);
    report.ik_error_max = std::max(report.ik_error_max, p.ik_error);
    if (p.ik_error > kReachTolerance) {
      char text[200];
      std::snprintf(text, sizeof text,
                    ": arm.base: expected the dig's path within the arm's reach (IK error at "
                    "most %.0f mm), got pass %d up to %.4g mm out of it; move arm.base or the path",
                    1e3 * kReachTolerance, pass, 1e3 * p.ik_error);
      throw InputError(scene_path + text);
    }
    if (announce && p.scale > 1)
      Status(
          "scoopsim: arm: pass %d: the path asks up to %.3g x the joint velocity limits "
          "(margin %.2g): slowed by %.3g, %.4g s -> %.4g s\n",
          pass, p.scale * spec.velocity_margin, spec.velocity_margin, p.scale, d, p.duration);
    if (announce && p.ik_error > 1e-3)
      Status(
          "scoopsim: arm: pass %d: the path is out of the arm's reach by up to %.3g mm (IK); "
          "move arm.base or the path\n",
          pass, 1e3 * p.ik_error);
    return plans.emplace(pass, std::move(p)).first->second;
  }

  // Reference at pass time t from a plan: linear between samples, held after the last.
  void Interpolate(const JointPlan& p, double t, size_t* segment) {
    const size_t last = p.t.size() - 1;
    if (last == 0 || t >= p.t[last]) {
      q_ref = p.q[last];
      qd_ref.setZero();
      return;
    }
    if (t <= p.t[0]) {
      q_ref = p.q[0];
      qd_ref.setZero();
      return;
    }
    size_t s = std::min(*segment, last - 1);
    if (p.t[s] > t) s = 0;
    while (s + 1 < last && p.t[s + 1] <= t) ++s;
    *segment = s;
    const double h = p.t[s + 1] - p.t[s];
    const double a = (t - p.t[s]) / h;
    for (int i = 0; i < n; ++i) {
      q_ref[i] = p.q[s][i] + a * (p.q[s + 1][i] - p.q[s][i]);
      qd_ref[i] = (p.q[s + 1][i] - p.q[s][i]) / h;
    }
  }

  void Reference(double t) {
    switch (mode) {
      case Mode::kFollow:
        if (external_ref) {  // ArmDriver::SetJointReference
          q_ref = external_q;
          qd_ref.setZero();
          break;
        }
        Interpolate(*plan, t, &seg);
        break;
      case Mode::kHold:
        q_ref = hold_q;
        qd_ref.setZero();
        break;
      case Mode::kRetract: {
        size_t s = 0;
        Interpolate(retract, t, &s);
        break;
      }
    }
  }

  dem::MeshMotion ScoopMotion() const {
    const Eigen::Isometry3d pose = bullet->BodyPose(scoop_body);
    const arm::Twist twist = bullet->BodyTwist(scoop_body);
    dem::MeshMotion m;
    m.pose.position = ToDem(pose.translation());
    m.pose.orientation = ToDem(Eigen::Quaterniond(pose.linear()));
    m.velocity = ToDem(twist.linear);
    m.angular_velocity = ToDem(twist.angular);
    return m;
  }

  // Contact of the scoop mesh with the fixed spheres: a linear spring-dashpot on the deepest
  // point of the mesh inside each sphere (compression only), world axes.
  void ObstacleContact(const dem::TriangleMesh& mesh) {
    contact_wrench = arm::Wrench{};
    if (obstacles.empty()) return;
    constexpr double kReachOfScoop = 0.25;  // no mesh point is further from l_scoop's origin [m]
    const dem::Pose& pose = cur.pose;
    for (const ObstacleSpec& o : obstacles) {
      if (dem::Norm(o.center - pose.position) > o.radius + kReachOfScoop) continue;
      const dem::Vec3 c = dem::ApplyInverse(pose, o.center);  // in l_scoop
      double deepest = 0;
      dem::Vec3 point;
      for (const auto& t : mesh.triangles) {
        const dem::ClosestPoint cp = dem::ClosestPointOnTriangle(
            c, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
        const double depth = o.radius - dem::Norm(cp.point - c);
        if (depth > deepest) {
          deepest = depth;
          point = cp.point;
        }
      }
      if (deepest <= 0) continue;
      const dem::Vec3 p = dem::Apply(pose, point);
      const dem::Vec3 normal =
          (1.0 / dem::Norm(p - o.center)) * (p - o.center);  // out of the sphere
      const dem::Vec3 v = cur.velocity + dem::Cross(cur.angular_velocity, p - pose.position);
      // Damping ratio 0.5 for the scoop's own mass (stable at the Bullet step: see ARCHITECTURE).
      const double damping = std::sqrt(o.stiffness * 0.31);
      const double fn = std::max(0.0, o.stiffness * deepest - damping * dem::Dot(v, normal));
      contact_wrench.force += fn * ToEigen(normal);
      contact_wrench.torque += ToEigen(dem::Cross(p, fn * normal));  // about the world origin
    }
    contact_wrench.point.setZero();
  }

  void SampleSensor() {
    if (sensor < 0) return;
    std::vector<arm::BodyWrench> external = {{scoop_body, dem_wrench},
                                             {scoop_body, contact_wrench}};
    std::vector<arm::Wrench> across;
    arm::InverseDynamics(model, bullet->q(), bullet->qd(), bullet->qdd(), ToEigen(gravity),
                         external, &across, base);
    // In the frame of the sensor's child body (the link after the joint), about the joint.
    const Eigen::Matrix3d r = bullet->BodyPose(sensor + 1).linear();
    ft_force = r.transpose() * across[sensor].force;
    ft_torque = r.transpose() * across[sensor].torque;
  }

  void React(const arm::ReactionCommand& command) {
    if (command.kind == arm::Reaction::kStopAndHold) {
      mode = Mode::kHold;
      hold_q = command.hold_positions;
      end_tau = std::min(end_tau, t_b + spec.stop_hold);
    } else if (command.kind == arm::Reaction::kRetract) {
      // A straight move of l_scoop from where it is, planned now (allocates, once).
      hold_q = command.hold_positions;
      mode = Mode::kHold;
      try {
        const double length = spec.retract_distance / spec.retract_speed;
        const int samples =
            static_cast<int>(std::clamp(std::ceil(length / kSample), 1.0, double{kMaxSamples}));
        const Eigen::Isometry3d start = bullet->BodyPose(scoop_body);
        const Eigen::Isometry3d to_base = base.inverse();
        std::vector<arm::PosePoint> points;
        for (int s = 0; s <= samples; ++s) {
          const double a = std::min(1.0, s * kSample / length);
          Eigen::Isometry3d pose = start;
          pose.translation() += a * spec.retract_distance * ToEigen(spec.retract_direction);
          points.push_back({t_b + a * length, to_base * pose});
        }
        const arm::JointPath jp = arm::FollowPosePath(model, model.tip_link, points, bullet->q());
        retract = JointPlan{};
        retract.t = jp.time;
        retract.q = jp.q;
        mode = Mode::kRetract;
        // The retract runs to its end even past the path's planned end (which cut it short).
        end_tau = t_b + length + spec.stop_hold;
      } catch (const std::exception& e) {
        Status("scoopsim: arm: retract not planned (%s): holding\n", e.what());
        end_tau = std::min(end_tau, t_b + spec.stop_hold);
      }
    }
  }

  // One Bullet step of k DEM steps.
  void Advance(const dem::TriangleMesh& mesh) {
    const double h = k * dt;
    if (count > 0) {
      dem_wrench.force = ToEigen(f_sum) / count;
      dem_wrench.torque = ToEigen(t_sum) / count;
      dem_wrench.point.setZero();
      f_sum = t_sum = dem::Vec3{};
      count = 0;
    }
    Reference(t_b);
    if (spec.implicit_d) {
      pid->ComputeServo(q_ref, qd_ref, bullet->q(), bullet->qd(), h, &servo);
      bullet->SetJointServo(servo);
    } else {
      pid->Compute(q_ref, qd_ref, bullet->q(), bullet->qd(), h, &demanded, &applied);
      bullet->SetJointTorques(applied);
    }
    bullet->ApplyWrench(scoop_body, dem_wrench);
    ObstacleContact(mesh);
    if (!obstacles.empty()) bullet->ApplyWrench(scoop_body, contact_wrench);
    bullet->Step(h);
    if (spec.implicit_d) {  // the torques at the end-of-step rates the step solved for
      arm::JointPid::Demanded(servo, bullet->qd(), &demanded);
      applied = bullet->motor_torques();
    }
    t_b += h;
    prev = cur;
    cur = ScoopMotion();
    ++report.bullet_steps;

    // The sensor at its own rate, held in between; the fault monitor every step.
    if (t_b >= next_ft - 1e-12) {
      SampleSensor();
      next_ft += 1.0 / spec.sensor_rate;
    }
    sample.time = Time(t_b);
    sample.step = h;
    for (int i = 0; i < n; ++i) {
      arm::JointSample& j = sample.joints[i];
      j.position = bullet->q()[i];
      j.velocity = bullet->qd()[i];
      j.demanded = demanded[i];
      j.applied = applied[i];
      report.peak_demanded[i] = std::max(report.peak_demanded[i], std::abs(demanded[i]));
    }
    sample.has_ft = sensor >= 0;
    sample.ft_force = ft_force;
    sample.ft_torque = ft_torque;
    const arm::FaultStep step = monitor->Update(sample);
    active = step.active;
    active_since.Add(step.active);
    if (step.new_events > 0) {
      const auto& events = monitor->events();
      for (size_t e = events.size() - step.new_events; e < events.size(); ++e) {
        const arm::FaultEvent& ev = events[e];
        report.events.push_back({ev.time, ev.flag, ev.joint, ev.value, ev.limit});
      }
    }
    report.latched = monitor->latched();
    // The time at saturation is the monitor's count (arm/fault_monitor.h), not counted again.
    std::copy(monitor->saturation_time().begin(), monitor->saturation_time().end(),
              report.saturation_time.begin());
    std::copy(monitor->first_saturation().begin(), monitor->first_saturation().end(),
              report.first_saturation.begin());
    if (step.new_command) React(monitor->command());

    // Tracking: the scoop against the tool path at the same (unscaled) path time.
    if (mode == Mode::kFollow && t_b <= plan->duration) {
      const dem::Pose want = path.MotionAt(t_b / plan->scale).pose;
      tracking = dem::Norm(cur.pose.position - want.position);
      const dem::Quat dq = want.orientation * dem::Conjugate(cur.pose.orientation);
      const double angle =
          2 * std::atan2(std::sqrt(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z), std::abs(dq.w));
      report.tracking_max = std::max(report.tracking_max, tracking);
      report.tracking_angle_max = std::max(report.tracking_angle_max, angle);
      track_sum2 += tracking * tracking;
      ++track_n;
      report.tracking_rms = std::sqrt(track_sum2 / track_n);
    }
  }
};

ArmDriver::ArmDriver(const Scene& scene, bool announce) {
  if (!scene.arm.enabled || !scene.arm.model || !scene.dig.enabled)
    throw std::invalid_argument("ArmDriver: the scene needs an arm: block and a dig: block");
  impl_ = std::make_unique<Impl>(scene);
  impl_->announce = announce;
}

ArmDriver::~ArmDriver() = default;

const ArmReport& ArmDriver::report() const { return impl_->report; }

double ArmDriver::PlannedDuration(int pass, const BedContext& bed) const {
  return impl_->Plan(pass, bed, impl_->dig).duration;
}

PassStart ArmDriver::BeginPass(int pass, const BedContext& bed) {
  Impl& a = *impl_;
  const JointPlan& plan = a.Plan(pass, bed, a.dig);
  a.path.BeginPass(pass, bed);  // the Cartesian path of this pass, for the tracking error
  a.mesh = bed.mesh;
  if (!a.bullet) {
    arm::BulletArmOptions options;
    options.gravity = ToEigen(a.gravity);
    options.base_pose = a.base;
    a.bullet = std::make_unique<arm::BulletArm>(a.model, options);
    std::vector<arm::PidGains> gains;
    for (const auto& g : a.spec.gains) gains.push_back({g[0], g[1], g[2]});
    a.pid = std::make_unique<arm::JointPid>(a.model, gains);
    arm::FaultRules rules;
    rules.torque_hold_time = a.spec.hold_time;
    rules.ft_joint = a.sensor >= 0 ? a.spec.sensor_joint : "";
    rules.force_limit = a.spec.force_limit;
    rules.torque_limit = a.spec.torque_limit;
    rules.on_torque_limit = rules.on_position_limit = rules.on_force_torque_limit =
        ToArm(a.spec.reaction);
    rules.retract_direction = a.base.linear().transpose() * ToEigen(a.spec.retract_direction);
    rules.retract_distance = a.spec.retract_distance;
    rules.retract_speed = a.spec.retract_speed;
    a.monitor = std::make_unique<arm::FaultMonitor>(a.model, rules);
    a.start_time = bed.start_time;
  } else {
    a.pass_offset += a.last_tau;
  }
  // At rest at the path's start, the integral holding the arm up against gravity.
  a.bullet->SetJointState(plan.q[0]);
  const Eigen::Vector3d g_base = a.base.linear().transpose() * ToEigen(a.gravity);
  a.pid->Preload(arm::GravityTorques(a.model, plan.q[0], g_base));
  // What the PID demands at rest there (its integral), shown before the first Bullet step (a
  // frame at the dig's start draws these torque bars); every step overwrites it.
  a.demanded = arm::GravityTorques(a.model, plan.q[0], g_base);
  for (int i = 0; i < a.n; ++i)
    a.applied[i] = std::clamp(a.demanded[i], -a.model.joints[i].effort, a.model.joints[i].effort);
  a.plan = &plan;
  a.seg = 0;
  a.mode = Impl::Mode::kFollow;
  a.end_tau = plan.duration;
  a.t_b = 0;
  a.cur = a.prev = a.ScoopMotion();
  a.sent_origin = a.cur.pose.position;
  a.f_sum = a.t_sum = dem::Vec3{};
  a.count = 0;
  a.dem_wrench = a.contact_wrench = arm::Wrench{};
  a.next_ft = 0;
  a.last_tau = 0;
  a.pass = pass;
  return {plan.duration, a.start_buried};
}

dem::MeshMotion ArmDriver::MotionAt(double tau) {
  Impl& a = *impl_;
  const double half = 0.5 * a.dt;
  // Bullet first: step Bullet up to tau, then hand the DEM the scoop where Bullet left it (the
  // copy of a.cur comes after the loop: taken before it, the DEM got the pose one Bullet step
  // old, FK(q - h qdot) instead of FK(q)).
  if (a.spec.timing == CouplingTiming::kBulletFirst)
    while (tau > a.t_b + half) a.Advance(*a.mesh);
  dem::MeshMotion m = a.cur;
  if (a.spec.timing == CouplingTiming::kBulletFirst) {
    if (a.k > 1 && tau < a.t_b - half) {
      // Between two Bullet states: linear in position and velocity, normalised-linear in
      // orientation.
      const double h = a.k * a.dt;
      const double s = std::clamp((tau - (a.t_b - h)) / h, 0.0, 1.0);
      const dem::MeshMotion& p = a.prev;
      const dem::MeshMotion& c = a.cur;
      m.pose.position = p.pose.position + s * (c.pose.position - p.pose.position);
      dem::Quat qc = c.pose.orientation;
      const dem::Quat& qp = p.pose.orientation;
      if (qp.w * qc.w + qp.x * qc.x + qp.y * qc.y + qp.z * qc.z < 0)
        qc = {-qc.w, -qc.x, -qc.y, -qc.z};
      m.pose.orientation = dem::Normalized({qp.w + s * (qc.w - qp.w), qp.x + s * (qc.x - qp.x),
                                            qp.y + s * (qc.y - qp.y), qp.z + s * (qc.z - qp.z)});
      m.velocity = p.velocity + s * (c.velocity - p.velocity);
      m.angular_velocity = p.angular_velocity + s * (c.angular_velocity - p.angular_velocity);
    }
  }
  a.sent_origin = m.pose.position;
  return m;
}

void ArmDriver::Feedback(double tau, const dem::MeshWrench& wrench) {
  Impl& a = *impl_;
  a.last_tau = tau;
  a.f_sum = a.f_sum + wrench.force;
  a.t_sum = a.t_sum + wrench.torque + dem::Cross(a.sent_origin, wrench.force);
  ++a.count;
  if (a.spec.timing == CouplingTiming::kDemFirst && a.count >= a.k) a.Advance(*a.mesh);
}

bool ArmDriver::PassOver(double tau) const { return !(tau < impl_->end_tau - 0.5 * impl_->dt); }

void ArmDriver::Record(H5Output* out, double time) {
  Impl& a = *impl_;
  if (!out) return;
  if (!a.attributes_written) {
    std::string joints;
    for (const std::string& j : a.report.joints) joints += (joints.empty() ? "" : ",") + j;
    out->SetAttribute("arm_urdf", a.spec.urdf);
    out->SetAttribute("arm_joints", joints);
    out->SetAttribute(
        "arm_timing",
        std::string(a.spec.timing == CouplingTiming::kBulletFirst ? "bullet_first" : "dem_first"));
    out->SetAttribute("arm_substeps", static_cast<double>(a.k));
    out->SetAttribute("arm_d_term", std::string(a.spec.implicit_d ? "implicit" : "explicit"));
    out->SetAttribute("arm_sensor_joint", a.spec.sensor_joint);
    const char* base_names[4] = {"arm_base_x", "arm_base_y", "arm_base_z", "arm_base_yaw"};
    for (int i = 0; i < 4; ++i) out->SetAttribute(base_names[i], a.report.base[i]);
    a.attributes_written = true;
  }
  const int n = a.n;
  out->AppendRow("/arm/time", &time, 1);
  out->AppendRow("/arm/joint_position", a.bullet->q().data(), n);
  out->AppendRow("/arm/joint_velocity", a.bullet->qd().data(), n);
  out->AppendRow("/arm/joint_reference", a.q_ref.data(), n);
  out->AppendRow("/arm/torque_demanded", a.demanded.data(), n);
  out->AppendRow("/arm/torque_applied", a.applied.data(), n);
  // The URDF's limit and the derate beside it (their product saturates; files before the derate
  // had its own dataset held the product here).
  out->AppendRow("/arm/effort_limit", a.report.urdf_effort_limit.data(), n);
  out->AppendRow("/arm/effort_derate", a.report.effort_derate.data(), n);
  const double ft[6] = {a.ft_force.x(),  a.ft_force.y(),  a.ft_force.z(),
                        a.ft_torque.x(), a.ft_torque.y(), a.ft_torque.z()};
  out->AppendRow("/arm/ft_sensor", ft, 6);
  // Every bit active at any step since the previous row: a fault that the stop reaction clears
  // within one row still shows.
  const uint64_t bits = a.active_since.Take() | a.active;  // the row's instant counts too
  out->AppendRow("/arm/fault_bits", &bits, 1);
  out->AppendRow("/arm/fault_latched", &a.report.latched, 1);
  out->AppendRow("/arm/tracking_error", &a.tracking, 1);
}

void ArmDriver::AddToView(WorldView* view) const {
  const Impl& a = *impl_;
  if (!a.bullet) return;
  const ArmBase base{{a.report.base[0], a.report.base[1], a.report.base[2]}, a.report.base[3]};
  a.geometry.AddToView(a.bullet->q().data(), base, view);
  for (int i = 0; i < a.n; ++i)
    view->joints.push_back({a.report.joints[i], a.demanded[i], a.report.effort_limit[i]});
  view->faults = FaultNames(a.report.latched);
}

std::vector<double> ArmDriver::JointPositions() const {
  if (!impl_->bullet) return {};
  const Eigen::VectorXd& q = impl_->bullet->q();
  return std::vector<double>(q.data(), q.data() + q.size());
}

void ArmDriver::SetJointReference(const std::vector<double>& q) {
  if (static_cast<int>(q.size()) != impl_->n) {
    throw std::invalid_argument("SetJointReference: expected " + std::to_string(impl_->n) +
                                " joint positions, got " + std::to_string(q.size()));
  }
  impl_->external_q = Eigen::Map<const Eigen::VectorXd>(q.data(), impl_->n);
  impl_->external_ref = true;
}

void ArmDriver::ClearJointReference() { impl_->external_ref = false; }

ArmDriver::JointState ArmDriver::joint_state() const {
  const Impl& a = *impl_;
  JointState s;
  if (!a.bullet) return s;
  auto list = [](const Eigen::VectorXd& v) {
    return std::vector<double>(v.data(), v.data() + v.size());
  };
  s.q = list(a.bullet->q());
  s.qd = list(a.bullet->qd());
  s.applied = list(a.applied);
  s.reference = list(a.q_ref);
  return s;
}

uint64_t ArmDriver::active_faults() const { return impl_->active; }
uint64_t ArmDriver::latched_faults() const { return impl_->report.latched; }

void ArmDriver::Finish(H5Output* out) {
  const ArmReport& r = impl_->report;
  const int n = impl_->n;
  std::vector<double> margin(n);
  for (int i = 0; i < n; ++i) margin[i] = r.effort_limit[i] - r.peak_demanded[i];
  Status(
      "scoopsim: arm: path slowed x%.3g; tracking |p - p_path| max %.3g mm, rms %.3g mm, "
      "angle max %.3g deg; %lld Bullet steps\n",
      r.time_scale, 1e3 * r.tracking_max, 1e3 * r.tracking_rms, r.tracking_angle_max * 180 / M_PI,
      static_cast<long long>(r.bullet_steps));
  Status(
      "scoopsim: arm: | joint | peak abs(demanded) [N m] | effort limit [N m] | margin [N m] | "
      "time at saturation [s] |\n");
  for (int i = 0; i < n; ++i)
    Status("scoopsim: arm: | %s | %.4g | %.4g | %.4g | %.4g |\n", r.joints[i].c_str(),
           r.peak_demanded[i], r.effort_limit[i], margin[i], r.saturation_time[i]);
  for (const ArmReport::Event& e : r.events)
    Status("scoopsim: arm: fault %s at t = %.4f s, joint %s: %.4g (limit %.4g)\n",
           arm::FaultName(e.flag), e.time,
           e.joint >= 0 && e.joint < n ? r.joints[e.joint].c_str() : "-", e.value, e.limit);
  if (r.events.empty()) Status("scoopsim: arm: no fault\n");
  if (!out) return;
  // The events as one table, always written (zero rows without a fault).
  using Column = H5Output::TableColumn;
  std::vector<Column> columns;
  for (const auto& [name, kind] : {std::pair{"time", Column::Kind::kFloat64},
                                   {"flag", Column::Kind::kUint64},
                                   {"flag_name", Column::Kind::kText},
                                   {"joint", Column::Kind::kInt32},
                                   {"joint_name", Column::Kind::kText},
                                   {"value", Column::Kind::kFloat64},
                                   {"limit", Column::Kind::kFloat64}}) {
    columns.emplace_back();
    columns.back().name = name;
    columns.back().kind = kind;
  }
  for (const ArmReport::Event& e : r.events) {
    columns[0].float64.push_back(e.time);
    columns[1].uint64.push_back(e.flag);
    columns[2].text.push_back(arm::FaultName(e.flag));
    columns[3].int32.push_back(e.joint);
    columns[4].text.push_back(e.joint >= 0 && e.joint < n ? r.joints[e.joint] : "-");
    columns[5].float64.push_back(e.value);
    columns[6].float64.push_back(e.limit);
  }
  out->WriteTable("/arm/fault_events", columns, static_cast<int64_t>(r.events.size()));
  out->SetCountAttribute("arm_fault_events", r.events.size());
  out->SetCountAttribute("arm_fault_latched", r.latched);
  out->AppendRow("/arm/report/peak_torque", r.peak_demanded.data(), n);
  out->AppendRow("/arm/report/effort_limit", r.urdf_effort_limit.data(), n);
  out->AppendRow("/arm/report/effort_derate", r.effort_derate.data(), n);
  out->AppendRow("/arm/report/margin", margin.data(), n);
  out->AppendRow("/arm/report/saturation_time", r.saturation_time.data(), n);
  out->SetAttribute("arm_time_scale", r.time_scale);
  out->SetAttribute("arm_tracking_max", r.tracking_max);
  out->SetAttribute("arm_tracking_rms", r.tracking_rms);
  out->SetAttribute("arm_tracking_angle_max", r.tracking_angle_max);
}

}  // namespace sim

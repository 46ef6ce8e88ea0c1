#include "arm/fault_monitor.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace arm {

namespace {
constexpr double kNoRun = std::numeric_limits<double>::quiet_NaN();
// Sample times are sums of steps: a hold reached "exactly" may fall short by rounding.
constexpr double kTimeSlack = 1e-9;  // [s]
}  // namespace

const char* FaultName(uint64_t flag) {
  switch (flag) {
    case kFaultNone:
      return "NONE";
    case kFaultHardware:
      return "HARDWARE";
    case kFaultTrajectoryGeneration:
      return "TRAJECTORY_GENERATION";
    case kFaultCollision:
      return "COLLISION";
    case kFaultEStop:
      return "E_STOP";
    case kFaultPositionLimit:
      return "POSITION_LIMIT";
    case kFaultJointTorqueLimit:
      return "JOINT_TORQUE_LIMIT";
    case kFaultVelocityLimit:
      return "VELOCITY_LIMIT";
    case kFaultNoForceData:
      return "NO_FORCE_DATA";
    case kFaultForceTorqueLimit:
      return "FORCE_TORQUE_LIMIT";
    default:
      return "";
  }
}

const char* ReactionName(Reaction reaction) {
  switch (reaction) {
    case Reaction::kContinue:
      return "continue";
    case Reaction::kStopAndHold:
      return "stop_and_hold";
    case Reaction::kRetract:
      return "retract";
  }
  return "";
}

FaultMonitor::FaultMonitor(const ArmModel& model, const FaultRules& rules)
    : joints_(model.joints), rules_(rules) {
  if (!rules_.ft_joint.empty()) {
    ft_joint_ = model.JointIndex(rules_.ft_joint);
    if (ft_joint_ < 0) {
      throw std::invalid_argument("FaultMonitor: the force/torque sensor's joint '" +
                                  rules_.ft_joint + "' is not a joint of the chain");
    }
  }
  events_.reserve(256);
  Reset();
}

void FaultMonitor::Reset() {
  const size_t n = joints_.size();
  run_start_.assign(n, kNoRun);
  saturation_time_.assign(n, 0.0);
  first_saturation_.assign(n, kNoRun);
  torque_on_.assign(n, false);
  position_on_.assign(n, false);
  velocity_on_.assign(n, false);
  force_on_ = torque_ft_on_ = no_data_on_ = false;
  latched_ = 0;
  events_.clear();
  command_ = ReactionCommand{};
}

void FaultMonitor::Raise(const ArmSample& s, uint64_t flag, int joint, double value, double limit,
                         Reaction reaction, FaultStep* step) {
  events_.push_back(FaultEvent{s.time, flag, joint, value, limit});
  latched_ |= flag;
  ++step->new_events;
  if (reaction > command_.kind) {
    command_.kind = reaction;
    command_.time = s.time;
    command_.flag = flag;
    command_.joint = joint;
    command_.hold_positions.resize(static_cast<Eigen::Index>(s.joints.size()));
    for (size_t i = 0; i < s.joints.size(); ++i) command_.hold_positions[i] = s.joints[i].position;
    if (reaction == Reaction::kRetract) {
      command_.retract_direction = rules_.retract_direction.normalized();
      command_.retract_distance = rules_.retract_distance;
      command_.retract_speed = rules_.retract_speed;
    } else {
      command_.retract_direction.setZero();
      command_.retract_distance = 0;
      command_.retract_speed = 0;
    }
    step->new_command = true;
  }
}

FaultStep FaultMonitor::Update(const ArmSample& s) {
  FaultStep step;
  const int n = static_cast<int>(joints_.size());
  for (int i = 0; i < n && i < static_cast<int>(s.joints.size()); ++i) {
    const Joint& j = joints_[i];
    const JointSample& x = s.joints[i];

    // JOINT_TORQUE_LIMIT: |demanded| >= effort held for torque_hold_time.
    const double demanded = std::abs(x.demanded);
    if (demanded >= j.effort) {
      saturation_time_[i] += s.step;
      if (std::isnan(first_saturation_[i])) first_saturation_[i] = s.time;
      if (std::isnan(run_start_[i])) run_start_[i] = s.time;
      if (s.time - run_start_[i] >= rules_.torque_hold_time - kTimeSlack) {
        if (!torque_on_[i]) {
          Raise(s, kFaultJointTorqueLimit, i, demanded, j.effort, rules_.on_torque_limit, &step);
        }
        torque_on_[i] = true;
        step.active |= kFaultJointTorqueLimit;
      }
    } else {
      run_start_[i] = kNoRun;
      torque_on_[i] = false;
    }

    // POSITION_LIMIT: outside [lower, upper] by more than the margin (revolute joints).
    bool position_out = false;
    double bound = 0;
    if (j.has_position_limits) {
      if (x.position < j.lower - rules_.position_margin) {
        position_out = true;
        bound = j.lower - rules_.position_margin;
      } else if (x.position > j.upper + rules_.position_margin) {
        position_out = true;
        bound = j.upper + rules_.position_margin;
      }
    }
    if (position_out) {
      if (!position_on_[i]) {
        Raise(s, kFaultPositionLimit, i, x.position, bound, rules_.on_position_limit, &step);
      }
      step.active |= kFaultPositionLimit;
    }
    position_on_[i] = position_out;

    // VELOCITY_LIMIT: |velocity| above the limit by more than the margin.
    const double v_limit = j.velocity * (1 + rules_.velocity_margin);
    const bool too_fast = std::abs(x.velocity) > v_limit;
    if (too_fast) {
      if (!velocity_on_[i]) {
        Raise(s, kFaultVelocityLimit, i, std::abs(x.velocity), v_limit, rules_.on_velocity_limit,
              &step);
      }
      step.active |= kFaultVelocityLimit;
    }
    velocity_on_[i] = too_fast;
  }

  // The force/torque sensor.
  if (ft_joint_ >= 0) {
    const bool no_data = !s.has_ft;
    if (no_data) {
      if (!no_data_on_)
        Raise(s, kFaultNoForceData, ft_joint_, 0, 0, rules_.on_no_force_data, &step);
      step.active |= kFaultNoForceData;
    }
    no_data_on_ = no_data;
    const double f = s.has_ft ? s.ft_force.norm() : 0;
    const double t = s.has_ft ? s.ft_torque.norm() : 0;
    const bool force_high = f >= rules_.force_limit;
    const bool torque_high = t >= rules_.torque_limit;
    if (force_high && !force_on_) {
      Raise(s, kFaultForceTorqueLimit, ft_joint_, f, rules_.force_limit,
            rules_.on_force_torque_limit, &step);
    }
    if (torque_high && !torque_ft_on_) {
      Raise(s, kFaultForceTorqueLimit, ft_joint_, t, rules_.torque_limit,
            rules_.on_force_torque_limit, &step);
    }
    if (force_high || torque_high) step.active |= kFaultForceTorqueLimit;
    force_on_ = force_high;
    torque_ft_on_ = torque_high;
  }
  step.latched = latched_;
  return step;
}

}  // namespace arm

// The arm's fault monitor: a pure function of the joint samples (no Bullet), fed one sample per
// step. Flags carry the lander's ArmFaultsStatus bit values (shared/FACTS.md section 6). The
// lander simulator has no detector for these: the rules are ours, exactly as follows.
//
// Per joint i with effort limit E_i, velocity limit V_i and, for revolute joints, position limits
// [L_i, U_i]; a sample at time t (times strictly increasing):
//
//   JOINT_TORQUE_LIMIT (32): let t0 be the time of the first sample of the current unbroken run
//     of samples with |demanded_i| >= E_i (demanded: the PID's output before the clamp). The flag
//     is raised at the first sample of that run with t - t0 >= torque_hold_time; it stays active
//     while the run lasts and drops at the first sample with |demanded_i| < E_i. So the event
//     comes within one sample interval after t0 + torque_hold_time, never before.
//     Event value |demanded_i| at that sample, limit E_i.
//   POSITION_LIMIT (16), revolute joints only (continuous joints have none): active while
//     position_i < L_i - position_margin or position_i > U_i + position_margin.
//     Event value position_i, limit the bound exceeded (with its margin).
//   VELOCITY_LIMIT (64): active while |velocity_i| > V_i (1 + velocity_margin).
//     Event value |velocity_i|, limit V_i (1 + velocity_margin).
//   FORCE_TORQUE_LIMIT (256), from the force/torque sensor at the joint named ft_joint (default
//     j_dist_pitch; the wrench carried across it, see arm::InverseDynamics): active while
//     |F| >= force_limit or |T| >= torque_limit (defaults 200 N and 100 N m, the lander's guarded
//     moves). Force and torque raise their own events (value |F| or |T|, their limit).
//   NO_FORCE_DATA (128): active while the sensor is monitored (ft_joint non-empty) and a sample
//     has no sensor wrench.
//
// Saturation, counted here and only here (the arm driver's report reads it): per joint, the time
// of the first sample with |demanded_i| >= E_i (first_saturation, NaN: none yet) and the sum of
// ArmSample::step over every such sample (saturation_time: the time spent at the limit).
//
// An event (time, flag, joint, value, limit) is recorded when a condition becomes active (a
// rising edge); it is not repeated while the condition lasts, and a new one is recorded if it
// ends and comes back. active bits: the conditions true at this sample; latched bits: every flag
// raised since the start (or Reset()).
//
// Reactions (scene-set per flag, data the caller acts on): kContinue (log only), kStopAndHold
// (hold every joint at its position of the event's sample: ReactionCommand::hold_positions, zero
// velocity), kRetract (hold, then move the scoop by retract_distance along retract_direction in
// the base frame at retract_speed; the caller plans it, e.g. arm::FollowPosePath). They are
// ordered kContinue < kStopAndHold < kRetract; an event whose reaction is stronger than any
// issued so far issues a new ReactionCommand (Update()'s new_command), weaker or equal ones are
// only recorded.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "arm/arm_model.h"

namespace arm {

// ArmFaultsStatus bit values (a uint64 bitmask).
enum ArmFault : uint64_t {
  kFaultNone = 0,
  kFaultHardware = 1,
  kFaultTrajectoryGeneration = 2,
  kFaultCollision = 4,
  kFaultEStop = 8,
  kFaultPositionLimit = 16,
  kFaultJointTorqueLimit = 32,
  kFaultVelocityLimit = 64,
  kFaultNoForceData = 128,
  kFaultForceTorqueLimit = 256,
};
// "JOINT_TORQUE_LIMIT" etc. for one bit; "" for an unknown one.
const char* FaultName(uint64_t flag);

enum class Reaction { kContinue = 0, kStopAndHold = 1, kRetract = 2 };
const char* ReactionName(Reaction reaction);

struct FaultRules {
  double torque_hold_time = 0.1;  // JOINT_TORQUE_LIMIT hold time [s]
  double position_margin = 0;     // [rad]
  double velocity_margin = 0.1;   // fraction of the velocity limit (Gazebo's rule lets a joint
                                  // overshoot it: it only stops pushing)
  std::string ft_joint = "j_dist_pitch";  // sensor joint; empty: no force/torque monitoring
  double force_limit = 200;               // [N]
  double torque_limit = 100;              // [N m]
  Reaction on_torque_limit = Reaction::kStopAndHold;
  Reaction on_position_limit = Reaction::kStopAndHold;
  Reaction on_velocity_limit = Reaction::kContinue;
  Reaction on_force_torque_limit = Reaction::kStopAndHold;
  Reaction on_no_force_data = Reaction::kContinue;
  Eigen::Vector3d retract_direction = Eigen::Vector3d::UnitZ();  // base frame, unit
  double retract_distance = 0.16;  // [m] (the lander's linear scoop retracts 0.16 m)
  double retract_speed = 0.01;     // [m/s]
};

struct JointSample {
  double position = 0;  // [rad]
  double velocity = 0;  // [rad/s]
  double demanded = 0;  // the controller's torque before the clamp [N m]
  double applied = 0;   // after it [N m]
};

struct ArmSample {
  double time = 0;                                     // [s]
  double step = 0;  // the time the sample stands for, the step that ended at it [s]
  std::vector<JointSample> joints;                     // dof() entries
  bool has_ft = false;                                 // whether the sensor wrench below is present
  Eigen::Vector3d ft_force = Eigen::Vector3d::Zero();  // [N]
  Eigen::Vector3d ft_torque = Eigen::Vector3d::Zero();  // [N m]
};

struct FaultEvent {
  double time = 0;
  uint64_t flag = 0;  // one ArmFault bit
  int joint = -1;     // chain joint index (the sensor's joint for force/torque flags)
  double value = 0;   // what was measured (see the rules)
  double limit = 0;   // what it was compared with
};

struct ReactionCommand {
  Reaction kind = Reaction::kContinue;
  double time = 0;                                               // of the event that issued it
  uint64_t flag = 0;                                             // that event's flag
  int joint = -1;                                                // and joint
  Eigen::VectorXd hold_positions;                                // joint positions to hold [rad]
  Eigen::Vector3d retract_direction = Eigen::Vector3d::UnitZ();  // kRetract only
  double retract_distance = 0;                                   // [m]
  double retract_speed = 0;                                      // [m/s]
};

struct FaultStep {
  uint64_t active = 0;       // conditions true at this sample
  uint64_t latched = 0;      // flags raised since the start
  int new_events = 0;        // events recorded by this sample (the last ones of events())
  bool new_command = false;  // this sample issued a stronger reaction (see command())
};

// The fault bits one output row shows: every bit active at any sample since the previous row
// (the OR over the interval), so that a fault the reaction clears within one row still shows.
class RowFaultBits {
 public:
  void Add(uint64_t active) { bits_ |= active; }
  // The bits since the last Take(), then starts over.
  uint64_t Take() {
    const uint64_t bits = bits_;
    bits_ = 0;
    return bits;
  }

 private:
  uint64_t bits_ = 0;
};

class FaultMonitor {
 public:
  // Limits from the model; throws std::invalid_argument for an ft_joint not in the chain.
  FaultMonitor(const ArmModel& model, const FaultRules& rules = {});
  FaultStep Update(const ArmSample& sample);
  void Reset();

  const std::vector<FaultEvent>& events() const { return events_; }
  uint64_t latched() const { return latched_; }
  const ReactionCommand& command() const { return command_; }
  const FaultRules& rules() const { return rules_; }
  // Per joint (see Saturation above): time at |demanded| >= effort [s], and its first sample's
  // time [s] (NaN: none).
  const std::vector<double>& saturation_time() const { return saturation_time_; }
  const std::vector<double>& first_saturation() const { return first_saturation_; }

 private:
  void Raise(const ArmSample& s, uint64_t flag, int joint, double value, double limit,
             Reaction reaction, FaultStep* step);

  std::vector<Joint> joints_;
  FaultRules rules_;
  int ft_joint_ = -1;
  // Per joint: start of the current run at or above the effort limit (NaN: none), whether the
  // torque, position and velocity conditions were active at the previous sample.
  std::vector<double> run_start_;
  std::vector<bool> torque_on_, position_on_, velocity_on_;
  std::vector<double> saturation_time_, first_saturation_;
  bool force_on_ = false, torque_ft_on_ = false, no_data_on_ = false;
  uint64_t latched_ = 0;
  std::vector<FaultEvent> events_;
  ReactionCommand command_;
};

}  // namespace arm

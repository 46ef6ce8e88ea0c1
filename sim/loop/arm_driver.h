// The arm in the loop: a ScoopDriver whose scoop is the last link of the lander's arm in Bullet
// (arm::BulletArm), driven by the lander's joint PID toward joint references, and pushed back by
// the DEM's wrench every step. The scene's `arm:` block sets it up (sim/input/scene.h, ArmSpec).
//
// The path. The dig's tool path, placed exactly as KinematicDriver places it (heading, pass depth,
// descent from above the bed), is sampled every 10 ms as poses of l_scoop, taken into the arm's
// base frame and turned into joint references by damped-least-squares IK (arm::FollowPosePath,
// each sample seeded by the previous; the first by arm.initial). The study's speeds (30-90 deg/s)
// are far above the arm's joint velocity limits (0.15-0.2 rad/s): the path is time-scaled, i.e.
// slowed uniformly by the factor s >= 1 that keeps every joint's reference rate at or below
// arm.velocity_margin (0.9) x its limit, so the PID tracks it closely instead of lagging behind a
// path it cannot follow (report().time_scale; 1 when the scene's path is already slow enough).
//
// Each Bullet step of h = arm.substeps x dt:
//   references q_ref(t), qd_ref(t) (linear between the samples; held after a stop or a retract)
//   PID -> demanded torque, clamped at the effort limit (derated by arm.derate) -> applied torque
//   (arm.d_term: implicit, the default on a wrench table: the D term at the step's end rate,
//   solved with the dynamics, arm/controller.h; demanded and applied are then the end-of-step
//   torques; coupled to the DEM the default stays explicit)
//   the DEM's wrench averaged over the DEM steps since the last Bullet step, and the contact of the
//   scoop with each fixed obstacle sphere (a linear penalty on the deepest point, damped), applied
//   to l_scoop; Bullet steps; the fault monitor takes the sample (arm/fault_monitor.h); the
//   force/torque sensor at arm.faults.sensor_joint is sampled at sensor_rate (arm::InverseDynamics
//   with Bullet's accelerations and the applied wrenches) and held between samples.
// Timing (ArmSpec::timing, docs/arm.md "The arm in the loop"): bullet_first (default) steps
// Bullet inside MotionAt with the wrench of the DEM steps before, so the DEM gets the pose at the
// end of its coming step (with substeps, poses between two Bullet states are interpolated);
// dem_first steps Bullet inside Feedback, so the DEM sees the pose one Bullet step old.
//
// Passes: each pass starts with the arm at rest at the IK of the path's first pose, the PID's
// integral preloaded with the gravity torques there (the arm was holding itself up before the
// pass). Reactions to a fault (arm.faults.reaction): stop holds every joint where it was and ends
// the pass stop_hold later; retract moves the scoop by retract distance along retract direction at
// retract speed, then holds and ends the pass stop_hold later.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/input/scene.h"
#include "sim/loop/scoop_driver.h"

namespace sim {

// What the arm did over a run (also written as /arm/ datasets and printed by Finish()).
struct ArmReport {
  std::vector<std::string> joints;
  std::vector<double> peak_demanded;     // max |demanded torque| per joint [N m]
  std::vector<double> effort_limit;      // per joint, derated: what saturates [N m]
  std::vector<double> urdf_effort_limit;  // per joint, the URDF's [N m] (/arm/effort_limit)
  std::vector<double> effort_derate;      // per joint, arm.derate (/arm/effort_derate); the
                                          // derated limit is their product
  std::vector<double> saturation_time;   // time with |demanded| >= effort limit, per joint [s]
  std::vector<double> first_saturation;  // time of the first step at or above it [s]; NaN: none
  struct Event {
    double time = 0;  // simulated time [s] (the /scoop/time clock)
    uint64_t flag = 0;
    int joint = -1;
    double value = 0, limit = 0;
  };
  std::vector<Event> events;  // arm::FaultMonitor's, in order
  uint64_t latched = 0;       // every flag raised
  double time_scale = 1;      // the path was slowed by this factor (largest over the passes)
  double ik_error_max = 0;    // largest IK position error along the path [m]
  // |p - p_path| of the l_scoop origin against the path at the same time, while following it
  // (not after a stop or retract) [m], and the largest angle between the orientations [rad].
  double tracking_max = 0, tracking_rms = 0, tracking_angle_max = 0;
  int64_t bullet_steps = 0;
  std::vector<double> base;  // base_link in the world: x, y, z [m], yaw [rad]
};

class ArmDriver : public ScoopDriver {
 public:
  // scene.arm.enabled and scene.dig.enabled (std::invalid_argument otherwise). `announce`: the
  // pass plans' notes on stderr (slowed to the velocity limits, slightly out of reach). A pass
  // path more than 50 mm out of reach throws InputError naming arm.base when it is planned.
  explicit ArmDriver(const Scene& scene, bool announce = true);
  ~ArmDriver() override;

  PassStart BeginPass(int pass, const BedContext& bed) override;
  dem::MeshMotion MotionAt(double tau) override;
  void Feedback(double tau, const dem::MeshWrench& wrench) override;
  bool PassOver(double tau) const override;
  double PlannedDuration(int pass, const BedContext& bed) const override;
  void Record(H5Output* out, double time) override;
  void Finish(H5Output* out) override;
  // The links but the scoop (sim/files/arm_geometry.h) at Bullet's joint positions, the demanded
  // torques against the effort limits, the latched fault flags.
  void AddToView(WorldView* view) const override;

  const ArmReport& report() const;
  // Bullet's joint positions now [rad] (dof; empty before the first pass).
  std::vector<double> JointPositions() const;

  // A controller outside the loop (the Python module's World.set_joint_reference): from the next
  // Bullet step on, the joint PID follows `q` [rad] (dof entries) at zero rate instead of the
  // path's IK, until ClearJointReference(); the fault reactions (stop: hold, retract) still take
  // over, and a pass still ends at its path's planned end. Unused, the driver is unchanged.
  void SetJointReference(const std::vector<double>& q);
  void ClearJointReference();
  // The last Bullet step's joint state (dof each; empty before the first pass): position [rad],
  // velocity [rad/s], the applied (clamped) torque [N m], and the reference it followed [rad].
  struct JointState {
    std::vector<double> q, qd, applied, reference;
  };
  JointState joint_state() const;
  // The fault conditions active at the last Bullet step and every flag latched so far
  // (arm/fault_monitor.h's ArmFault bits).
  uint64_t active_faults() const;
  uint64_t latched_faults() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim

#include <algorithm>

#include "sim/loop/dig.h"
#include "sim/loop/scoop_driver.h"

namespace sim {
namespace {

// Level orientation of the scoop (l_scoop +x forward, +z down): rpy (pi, 0, 0).
const dem::Quat kLevel{0.0, 1.0, 0.0, 0.0};

double LowestZ(const dem::TriangleMesh& mesh, const dem::Pose& pose) {
  double z = 1e300;
  for (const dem::Vec3& v : mesh.vertices) z = std::min(z, dem::Apply(pose, v).z);
  return z;
}

// The descent from above the bed goes at the approach's speed (the first move's, when it
// translates), else at the study's 0.14 m/s.
double ApproachSpeed(const TrajectorySpec& path) {
  return !path.moves.empty() && path.moves[0].kind == Move::Kind::kTranslate ? path.moves[0].speed
                                                                               : 0.14;
}

}  // namespace

KinematicDriver::KinematicDriver(const TrajectorySpec& path, double heading, double bite_depth,
                                 bool start_buried)
    : path_(path),
      reference_(path),
      heading_(dem::AxisAngle({0, 0, 1}, heading)),
      origin_shift_{path.pivot_start.x, path.pivot_start.y, 0},
      bite_depth_(bite_depth),
      start_buried_(start_buried),
      approach_speed_(ApproachSpeed(reference_.spec())) {}

std::unique_ptr<KinematicDriver> KinematicDriver::ForDig(const DigSpec& dig) {
  return std::make_unique<KinematicDriver>(dig.trajectory, dig.heading, dig.bite_depth,
                                           dig.start_buried);
}

dem::Pose KinematicDriver::Place(const ScoopKinematics& k, const dem::Vec3& extra) const {
  dem::Pose p;
  p.position = origin_shift_ + dem::Rotate(heading_, k.pose.position - origin_shift_) + extra;
  p.orientation = heading_ * k.pose.orientation;
  return p;
}

KinematicDriver::Plan KinematicDriver::PlanPass(int pass, const BedContext& bed) const {
  // Where the pass goes: the level scoop's lowest point at pass * bite below the surface, once
  // the path's leading translations (the approach) are done.
  const double lowest_level = LowestBelowPivot(*bed.mesh, kLevel, path_.pivot_offset);
  TrajectorySpec spec = path_;
  spec.pivot_start.z = bed.surface - pass * bite_depth_ - lowest_level;
  spec.pivot_start.z -= reference_.LeadingDrop();
  Plan plan{Trajectory(spec)};
  if (!start_buried_) {
    const dem::Pose first = Place(plan.trajectory.At(plan.trajectory.start_time()), {});
    plan.lift = std::max(0.0, bed.clear_z - LowestZ(*bed.mesh, first));
    plan.descent_speed = approach_speed_;
    plan.descent_time = plan.lift / approach_speed_;
  }
  return plan;
}

PassStart KinematicDriver::BeginPass(int pass, const BedContext& bed) {
  plan_ = std::make_unique<Plan>(PlanPass(pass, bed));
  time_step_ = bed.time_step;
  return {plan_->Duration(), start_buried_};
}

double KinematicDriver::PlannedDuration(int pass, const BedContext& bed) const {
  return PlanPass(pass, bed).Duration();
}

bool KinematicDriver::PassOver(double tau) const {
  return !(tau < plan_->Duration() - 0.5 * time_step_);
}

dem::MeshMotion KinematicDriver::MotionAt(double tau) {
  const Plan& plan = *plan_;
  const double offset = plan.trajectory.start_time();
  ScoopKinematics k;
  dem::Vec3 extra;  // descent offset (world z)
  if (tau < plan.descent_time) {
    k = plan.trajectory.At(offset);
    extra = {0, 0, plan.lift - plan.descent_speed * tau};
    k.velocity = {0, 0, -plan.descent_speed};
    k.angular_velocity = {};
  } else {
    k = plan.trajectory.At(tau - plan.descent_time + offset);
  }
  // Heading: rotate the whole path about the vertical through its start.
  dem::MeshMotion m;
  m.pose = Place(k, extra);
  m.velocity = dem::Rotate(heading_, k.velocity);
  m.angular_velocity = dem::Rotate(heading_, k.angular_velocity);
  return m;
}

}  // namespace sim

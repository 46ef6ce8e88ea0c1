// Where the scoop is each step: the seam between the run loop (sim::World) and whatever moves the
// scoop. The kinematic driver follows a prescribed tool path (sim/input/trajectory.h); the Bullet
// arm and the table-driven arm plug in beside it without touching the loop.
//
// The loop's calls, for each pass p = 1..passes:
//   BeginPass(p, bed)            once, on the bed as the previous pass left it
//   repeat while !PassOver(tau):
//     MotionAt(tau + dt)         the scoop's pose and twist at the end of the coming step,
//                                called inside that DEM step (dem::System::Step's `motion`), on
//                                one of its threads while the others compute pair forces: it
//                                must not touch the DEM system
//     Feedback(tau + dt, wrench) what the particles did to the scoop over that step
// where tau is the time since the pass began. A driver never throws inside the loop.
// Output: Record(out, time) each time the loop writes a /scoop/ row, Finish(out) once when the run
// ends (out may be null there: no file), both outside Step()'s hot path.
//
// A driver that brings the scoop's wrench itself (the arm on a wrench table, sim/loop/table_arm.h)
// says so with OwnStep() > 0: the loop then has no bed and steps no DEM. Each of its steps is
//   MotionAt(tau + h)            as above (the loop's clock moves to the pass's start + tau + h)
//   w = OwnWrench(pose)          the driver's wrench at the pose MotionAt gave
//   Feedback(tau + h, w)
// with h = OwnStep() and tau + h = (steps into the pass) x h, so the clock does not drift.
// The loop's choice of driver for a scene is made in one place: MakeScoopDriver below.
#pragma once

#include <memory>

#include "dem/mesh.h"
#include "dem/system.h"
#include "sim/input/scene.h"
#include "sim/input/trajectory.h"
#include "sim/files/world_view.h"

namespace sim {

class H5Output;

// What a driver knows of the bed and the scoop when a pass begins.
struct BedContext {
  const dem::TriangleMesh* mesh = nullptr;  // the scoop, in l_scoop coordinates
  double surface = 0;                       // world z of the original free surface [m]
  double clear_z = 0;     // world z above every particle with a margin: the scoop starts above
                          // it when it is lowered into the bed [m]
  double time_step = 0;   // [s]
  double start_time = 0;  // simulated time at which the dig began (pass 1's tau = 0) [s]
};

// How a pass starts.
struct PassStart {
  double duration = 0;        // planned length of the pass [s] (its end is PassOver's call)
  bool start_buried = false;  // the scoop is placed in the bed at MotionAt(0): the loop removes
                              // the particles it overlaps first
};

class ScoopDriver {
 public:
  virtual ~ScoopDriver() = default;
  // Plans pass `pass` (1-based).
  virtual PassStart BeginPass(int pass, const BedContext& bed) = 0;
  // The scoop's motion at `tau` seconds into the current pass.
  virtual dem::MeshMotion MotionAt(double tau) = 0;
  // The wrench of the particles on the scoop over the step that ended at `tau` (world frame,
  // about the mesh origin MotionAt(tau).pose.position). The kinematic driver ignores it.
  virtual void Feedback(double tau, const dem::MeshWrench& wrench) {
    (void)tau;
    (void)wrench;
  }
  // The loop's step [s] when the driver brings its own wrench (no bed, no DEM step); 0 (the
  // default): the DEM's wrench and the DEM's step.
  virtual double OwnStep() const { return 0; }
  // With OwnStep() > 0: the wrench on the scoop at `pose` (l_scoop in the world, the pose
  // MotionAt just gave), called once a step, as dem::MeshWrench (world axes, torque about
  // pose.position); its `contacts` is 1 while the driver's source is in contact, else 0.
  virtual dem::MeshWrench OwnWrench(const dem::Pose& pose) {
    (void)pose;
    return {};
  }
  // Whether the current pass has ended at `tau`.
  virtual bool PassOver(double tau) const = 0;
  // The planned length of pass `pass` [s], before it begins (for the progress line).
  virtual double PlannedDuration(int pass, const BedContext& bed) const = 0;
  // The driver's own rows, written with each /scoop/ row at simulated time `time` (the arm's
  // /arm/ datasets); may throw (the loop turns it into kOutputFailed).
  virtual void Record(H5Output* out, double time) {
    (void)out;
    (void)time;
  }
  // The run is over: the driver's summary on stderr and, with `out`, in the file.
  virtual void Finish(H5Output* out) { (void)out; }
  // What the driver adds to a view of the world (frames, snapshots): the arm's links, its joint
  // torques and fault flags. The view may point into the driver until its next step.
  virtual void AddToView(WorldView* view) const { (void)view; }
};

// The study's way: the scoop follows a tool path (Tables 1 and 4, or any list of moves), turned
// by the dig's heading about the vertical through the path's start and lowered per pass so that
// pass p cuts p * bite_depth below the original surface. Each pass starts with the path's first
// move; unless the dig starts buried, a vertical descent at the approach speed brings the scoop
// from above the bed (BedContext::clear_z) down to that start pose.
class KinematicDriver : public ScoopDriver {
 public:
  // `path`: the dig's trajectory (pivot_start.z is set per pass); heading [rad] about world z;
  // bite_depth [m]; start_buried: see PassStart.
  KinematicDriver(const TrajectorySpec& path, double heading, double bite_depth, bool start_buried);
  // The driver of a scene's dig block (its trajectory, heading, bite depth and start_buried).
  static std::unique_ptr<KinematicDriver> ForDig(const DigSpec& dig);

  PassStart BeginPass(int pass, const BedContext& bed) override;
  dem::MeshMotion MotionAt(double tau) override;
  bool PassOver(double tau) const override;
  double PlannedDuration(int pass, const BedContext& bed) const override;

 private:
  // One pass: the path placed at its depth, shifted in time by the descent.
  struct Plan {
    Trajectory trajectory;
    double descent_time = 0;   // [s]
    double descent_speed = 0;  // [m/s]
    double lift = 0;           // height of the start pose above the path's first pose [m]
    double Duration() const {
      return descent_time + trajectory.end_time() - trajectory.start_time();
    }
  };
  Plan PlanPass(int pass, const BedContext& bed) const;
  // The pose of a path state turned by the heading about the vertical through the path's start,
  // then shifted by `extra` (the descent) [m].
  dem::Pose Place(const ScoopKinematics& k, const dem::Vec3& extra) const;

  TrajectorySpec path_;
  Trajectory reference_;  // the path as given (validated once)
  dem::Quat heading_;     // rotation about world z
  dem::Vec3 origin_shift_;
  double bite_depth_;
  bool start_buried_;
  double approach_speed_;
  double time_step_ = 0;
  std::unique_ptr<Plan> plan_;  // the current pass
};

// The scene's driver, chosen here and nowhere else: none without a dig; the arm on a wrench table
// (arm.wrench: table, TableArmDriver), the arm coupled to the DEM (arm:, ArmDriver), or the
// scoop on its tool path (KinematicDriver). `announce`: the arm's plan notes on stderr. Throws
// InputError for a table that does not cover the dig (an arm's path out of its reach is refused
// when its pass is planned: PlannedDuration, BeginPass).
std::unique_ptr<ScoopDriver> MakeScoopDriver(const Scene& scene, bool announce = true);

}  // namespace sim

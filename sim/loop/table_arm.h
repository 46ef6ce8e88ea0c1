// The table-driven arm (issue 20 item 4): the arm of sim/loop/arm_driver.h digs with its scoop
// wrench taken from a wrench table (sim/files/wrench_table.h) instead of the DEM: no bed, no
// particles, only Bullet, the path, the IK, the PID and the fault monitor, for torque-limit fault
// testing far faster than real time. A scene selects it with
//   arm: {wrench: table, table: out/lookup/table.h5}      (default wrench: dem)
// and needs dig.surface (the bed's free surface height [m]: there is no bed to measure it on).
//
// The loop: World::Step, as for every dig (TableArmDriver below, chosen by MakeScoopDriver), with
// one loop step per Bullet step h = arm.step (else arm.substeps x time_step, the coupled run's arm
// step; the DEM's time step still comes from bed.radius), the table's wrench standing in for the
// DEM's and no DEM stepped:
//   MotionAt(tau + h)        Bullet steps (on the wrench of the previous step, as bullet_first)
//   OwnWrench(pose)          TableWrench::At: the table's wrench at the scoop's new pose
//   Feedback(tau + h, W)     to be applied over the next Bullet step
// so the arm sees the wrench with the same one-step lag as in the coupled run.
//
// The wrench (TableWrench), per pass p: Query(bed.material, dig.bite_depth in mm, p, rho), the
// table's l_scoop-frame wrench about the CoM, turned into world axes and taken about the l_scoop
// origin (what Feedback expects, as dem::MeshWrench); rho as the table defines it (its
// rho_definition) since first contact: the length of the CoM's path (path), or the running
// maximum of the CoM's horizontal displacement along the trench, the dig's heading (along). First
// contact has no particles to detect it: it is the first step at which a vertex of the scoop mesh
// is at or below the floor the pass meets, surface - (p - 1) x bite_depth (the original surface for
// pass 1, the previous pass's cut after; a start_buried pass touches at once). Before it the wrench
// is zero.
//
// Out of the table's domain: what can be checked before the run is refused there, with one line
// naming the table file (InputError, exit 2): a material, a pass or a bite depth the table does
// not hold (a bite depth between two of the table's is interpolated linearly, as Query does; one
// outside them is not extrapolated nor clamped: that would silently use another depth's data). rho
// past the end of a pass's data is clamped: the wrench holds the pass's last value (the DEM's
// scoop was lifting out there, holding its sample; the lander's nearest-key lookup does the same),
// and the steps where it held are counted and reported.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "dem/mesh.h"
#include "dem/system.h"
#include "sim/files/wrench_table.h"
#include "sim/input/scene.h"
#include "sim/loop/arm_driver.h"
#include "sim/loop/scoop_driver.h"

namespace sim {

// The table's wrench on the scoop along a pass (usable alone, e.g. by tests).
class TableWrench {
 public:
  // Loads scene.arm.table and checks material, bite depth and every pass of the dig against it
  // (InputError naming the table, the scene and the key otherwise).
  explicit TableWrench(const Scene& scene);

  // A new pass: no contact yet, rho 0.
  void BeginPass(int pass);
  // The wrench at the scoop's pose `pose` (l_scoop in the world): world force [N] and torque
  // about pose.position [N m], contacts 1 after first contact, else all zero. Updates rho.
  dem::MeshWrench At(const dem::Pose& pose);

  bool touched() const { return touched_; }
  double rho() const { return rho_; }  // [m]
  // The last wrench in the table's frame: l_scoop axes, about the CoM [N], [N m].
  const std::array<double, 6>& scoop_wrench() const { return scoop_wrench_; }
  const dem::Vec3& com() const { return com_; }       // CoM of the last pose, world [m]
  int64_t held_steps() const { return held_steps_; }  // steps with rho past the pass's data
  const WrenchTable& table() const { return table_; }

 private:
  WrenchTable table_;
  std::string material_;
  double bite_depth_mm_ = 0;
  double surface_ = 0, bite_depth_ = 0;  // [m]
  dem::Vec3 com_scoop_;                  // CoM in l_scoop [m]
  dem::Vec3 trench_;                     // unit digging direction, world
  const dem::TriangleMesh* mesh_;        // the scoop, l_scoop coordinates
  int pass_ = 0;
  double floor_ = 0;  // z of first contact in this pass [m]
  bool touched_ = false;
  double along0_ = 0, rho_ = 0;  // CoM along the trench at first contact; rho [m]
  dem::Vec3 com_last_;           // CoM at the last step (rho as a path length) [m]
  double rho_end_ = 0;           // end of this pass's data (the slower of the cells) [m]
  dem::Vec3 com_;
  std::array<double, 6> scoop_wrench_{};
  int64_t held_steps_ = 0;
};

// The arm on the table as a ScoopDriver: the ArmDriver of a copy of the scene with time_step =
// the arm's step h (arm.step, else arm.substeps x the DEM's step), one substep, bullet_first, its
// wrench the TableWrench's at each new pose (OwnStep() = h, OwnWrench = TableWrench::At). World
// runs it as any dig (sim/loop/world.h): no bed, no DEM step, the same /scoop/ and /arm/ rows as a
// coupled arm dig (/scoop/contacts 0: no particles), plus root attributes wrench_source =
// "table", wrench_table, arm_step and, at the end, real_time_factor (simulated over wall time
// from the first pass's start).
class TableArmDriver : public ScoopDriver {
 public:
  // Throws InputError (a table that does not cover the dig: see TableWrench).
  explicit TableArmDriver(const Scene& scene, bool announce = true);
  ~TableArmDriver() override;

  double OwnStep() const override { return step_; }
  dem::MeshWrench OwnWrench(const dem::Pose& pose) override { return source_.At(pose); }
  PassStart BeginPass(int pass, const BedContext& bed) override;
  dem::MeshMotion MotionAt(double tau) override { return arm_.MotionAt(tau); }
  void Feedback(double tau, const dem::MeshWrench& wrench) override;
  bool PassOver(double tau) const override { return arm_.PassOver(tau); }
  double PlannedDuration(int pass, const BedContext& bed) const override {
    return arm_.PlannedDuration(pass, bed);
  }
  void Record(H5Output* out, double time) override;
  void Finish(H5Output* out) override;
  void AddToView(WorldView* view) const override { arm_.AddToView(view); }

  const ArmDriver& arm() const { return arm_; }
  const TableWrench& source() const { return source_; }

 private:
  static Scene ArmScene(const Scene& scene);  // the scene the arm steps in (above)

  Scene scene_;  // the table scene (TableWrench points into its scoop mesh)
  double step_;  // h [s]
  TableWrench source_;
  ArmDriver arm_;
  bool attributes_written_ = false;
  bool started_ = false;
  std::chrono::steady_clock::time_point wall0_;  // the first pass's start
  double passes_time_ = 0;  // simulated time of the passes before the current one [s]
  double last_tau_ = 0;     // of the current pass's last step [s]
};

}  // namespace sim

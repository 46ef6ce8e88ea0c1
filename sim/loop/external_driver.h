// A scoop moved from outside the loop, step by step: the Python module's World.set_scoop_pose (a
// driver written in Python). The pose (and twist) set last is the scoop's at the end of every
// coming step until the next one is set; a pass lasts until EndPass(). No physics of its own: the
// particles' wrench is kept for the caller (World::scoop_wrench()).
#pragma once

#include "dem/mesh.h"
#include "sim/input/scene.h"
#include "sim/loop/scoop_driver.h"

namespace sim {

class ExternalPoseDriver : public ScoopDriver {
 public:
  // Until a pose is set, the scoop waits level above the bed (BedContext::clear_z) at the
  // centre of `scene`'s box.
  explicit ExternalPoseDriver(const Scene& scene);

  // The pose (l_scoop in the world, orientation w x y z) and twist (world frame: [m/s], [rad/s])
  // for the coming steps. Between steps only (not while World::Step() runs).
  void SetMotion(const dem::MeshMotion& motion) {
    motion_ = motion;
    pose_set_ = true;
  }
  // Ends the current pass at its next step (the loop then takes the sample and begins the next).
  void EndPass() { end_pass_ = true; }

  PassStart BeginPass(int pass, const BedContext& bed) override;
  dem::MeshMotion MotionAt(double tau) override {
    (void)tau;
    return motion_;
  }
  bool PassOver(double tau) const override {
    (void)tau;
    return end_pass_;
  }
  double PlannedDuration(int pass, const BedContext& bed) const override {
    (void)pass;
    (void)bed;
    return 0;  // unknown: as long as the caller steps
  }

 private:
  dem::Vec3 centre_;  // of the box (x, y) [m]
  dem::MeshMotion motion_;
  bool pose_set_ = false;
  bool end_pass_ = false;
};

}  // namespace sim

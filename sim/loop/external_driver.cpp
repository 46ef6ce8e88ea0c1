#include "sim/loop/external_driver.h"

namespace sim {

ExternalPoseDriver::ExternalPoseDriver(const Scene& scene)
    : centre_{0.5 * (scene.box_min.x + scene.box_max.x), 0.5 * (scene.box_min.y + scene.box_max.y),
              0} {}

PassStart ExternalPoseDriver::BeginPass(int pass, const BedContext& bed) {
  (void)pass;
  end_pass_ = false;
  if (!pose_set_) {
    motion_ = dem::MeshMotion{};
    motion_.pose.position = {centre_.x, centre_.y, bed.clear_z};
  }
  return {};
}

}  // namespace sim

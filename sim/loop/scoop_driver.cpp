// The one place a scene's driver is chosen (sim/loop/scoop_driver.h).
#include "sim/loop/scoop_driver.h"

#include "sim/loop/arm_driver.h"
#include "sim/loop/table_arm.h"

namespace sim {

std::unique_ptr<ScoopDriver> MakeScoopDriver(const Scene& scene, bool announce) {
  if (!scene.dig.enabled) return nullptr;
  if (scene.arm.enabled && scene.arm.table_driven)
    return std::make_unique<TableArmDriver>(scene, announce);
  if (scene.arm.enabled) return std::make_unique<ArmDriver>(scene, announce);
  return KinematicDriver::ForDig(scene.dig);
}

}  // namespace sim

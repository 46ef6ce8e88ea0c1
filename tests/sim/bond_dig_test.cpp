// The arm meeting sintered ice (issue 44 item 5): scenes/fault/sintered_ice.yaml against its
// unbonded control scenes/fault/unbonded_ice.yaml, on one bed poured once from the control's
// bed: block (the sintered scene bonds it when it loads it).
//   - the unbonded bed raises no fault, and j_prox_pitch's peak demand stays under half its
//     derated limit (found ~10 of 36.5 N m);
//   - the sintered bed raises JOINT_TORQUE_LIMIT first, on j_prox_pitch, one hold time after its
//     demand first reached the limit (the fault monitor's rule, within one Bullet step), while
//     the scoop's |F| is still under the F/T sensor's 200 N (so the joint, not the sensor, is
//     what trips), between 0.3 and 1.2 s into the dig (found 0.73 s: 0.2 s hold, then the push);
//   - the sintered dig ends in the same DEM state hash on 1 and 2 threads (bonds, arm and DEM
//     coupled; dem's bond tests check the bonds alone).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "sim/files/bed_io.h"
#include "sim/input/scene.h"
#include "sim/loop/arm_driver.h"
#include "sim/loop/world.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;
constexpr uint64_t kJointTorqueLimit = 32;
constexpr int kProxPitch = 2;  // j_prox_pitch in the chain

sim::Scene Scene(const std::string& name) {
  return sim::LoadScene(kSourceDir + "/scenes/fault/" + name);
}

// The control's bed, poured once on 2 threads.
const std::string& Bed() {
  static const std::string path = [] {
    const fs::path dir = scoopsim_test::ProcessTempDir("bond_dig");
    const sim::Scene scene = Scene("unbonded_ice.yaml");
    sim::World world(scene, 2);
    sim::SettleReport report;
    const int status = world.Pour(true, &report);
    EXPECT_TRUE(status == 0 || status == 4) << status;
    const std::string bed = (dir / "ice.h5").string();
    sim::SaveBed(bed, world.system(), scene.yaml_text);
    return bed;
  }();
  return path;
}

struct ArmDig {
  sim::ArmReport arm;
  uint64_t hash = 0;
  double dig_start = 0;
  std::vector<double> time;   // after each step [s]
  std::vector<double> force;  // |F| of the scoop's last step [N]
};

ArmDig Dig(const std::string& name, int threads) {
  const sim::Scene scene = Scene(name);
  sim::World world(scene, threads);
  world.LoadBed(Bed());
  auto driver = std::make_unique<sim::ArmDriver>(scene, false);
  const sim::ArmDriver* arm = driver.get();
  ArmDig run;
  run.dig_start = world.system().time();
  world.StartDig(std::move(driver));
  while (!world.Done()) {
    const dem::StepStatus status = world.Step();
    EXPECT_TRUE(status.ok()) << status.message;
    if (!status.ok()) break;
    run.time.push_back(world.system().time());
    run.force.push_back(dem::Norm(world.system().mesh_wrench(0).force));
  }
  run.arm = arm->report();
  run.hash = world.system().StateHash();
  return run;
}

TEST(BondDigTest, SinteredIceRaisesJointTorqueLimitWhereUnbondedIceDoesNot) {
  const ArmDig loose = Dig("unbonded_ice.yaml", 1);
  EXPECT_TRUE(loose.arm.events.empty());
  EXPECT_EQ(loose.arm.latched, 0u);
  const double limit = loose.arm.effort_limit[kProxPitch];
  EXPECT_LT(loose.arm.peak_demanded[kProxPitch], 0.5 * limit);

  const sim::Scene scene = Scene("sintered_ice.yaml");
  const ArmDig sintered = Dig("sintered_ice.yaml", 1);
  ASSERT_FALSE(sintered.arm.events.empty());
  const sim::ArmReport::Event& e = sintered.arm.events.front();
  EXPECT_EQ(e.flag, kJointTorqueLimit);
  EXPECT_EQ(e.joint, kProxPitch);
  EXPECT_EQ(e.limit, limit);
  const double first = sintered.arm.first_saturation[kProxPitch];
  const double h = scene.arm.substeps * scene.time_step;
  EXPECT_GE(e.time - first, scene.arm.hold_time - 1e-9);
  EXPECT_LE(e.time - first, scene.arm.hold_time + h + 1e-9);
  EXPECT_GE(e.time - sintered.dig_start, 0.3);
  EXPECT_LE(e.time - sintered.dig_start, 1.2);
  double peak_force = 0;
  for (size_t i = 0; i < sintered.time.size() && sintered.time[i] <= e.time; ++i)
    peak_force = std::max(peak_force, sintered.force[i]);
  EXPECT_LT(peak_force, scene.arm.force_limit);
  std::printf(
      "unbonded: peak j_prox_pitch demand %.4g of %.4g N m, no fault; sintered: "
      "JOINT_TORQUE_LIMIT at %.4f s into the dig (demand %.4g N m), |F| up to %.4g N by then\n",
      loose.arm.peak_demanded[kProxPitch], limit, e.time - sintered.dig_start, e.value, peak_force);

  const ArmDig two = Dig("sintered_ice.yaml", 2);
  EXPECT_EQ(two.hash, sintered.hash);
  EXPECT_EQ(two.arm.events.front().time, e.time);
}

}  // namespace

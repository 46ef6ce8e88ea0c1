// The kinematic scoop driver (sim/loop/kinematic_driver.cpp) against closed forms written out here,
// and a tool path the study's four segments cannot express, dug end to end.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/input/exit_status.h"
#include "sim/input/scene.h"
#include "sim/loop/scoop_driver.h"
#include "sim/loop/world.h"

namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 1e-12;  // [m], [m/s], [-]

void ExpectVecNear(const dem::Vec3& got, const dem::Vec3& want, double tol, const std::string& what) {
  EXPECT_NEAR(got.x, want.x, tol) << what;
  EXPECT_NEAR(got.y, want.y, tol) << what;
  EXPECT_NEAR(got.z, want.z, tol) << what;
}

// A path of one horizontal push (+x, 0.1 m/s over 0.1 m from t = 0) at pitch 0, dug along
// heading 90 deg, pass 2 with a bite of 0.02 m below a surface at z = 0.1, lowered from
// clear_z = 0.3. Written out: the level scoop's lowest point lies h = max(v.z) below the pivot
// (R0 = diag(1, -1, -1)), so the pass's start pose has the pivot at z0 = 0.1 - 2 (0.02) + h,
// raised by lift = 0.3 - (0.1 - 0.04) for the descent, which goes down at the first move's
// speed, 0.1 m/s, for lift / 0.1 s. Then the pivot moves along R_z(90 deg) x = +y at 0.1 m/s.
TEST(KinematicDriverTest, DescentAndHeadingMatchClosedForm) {
  dem::TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0.01}, {0.1, 0, 0.03}, {0, 0.05, 0.02}, {0.05, 0.02, 0.07}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  TrajectorySpec path;
  path.pivot_start = {0.2, 0.15, 0};
  path.initial_pitch = 0;
  path.moves = {Translate("push", {1, 0, 0}, 0.1, 0.1, 0.0)};
  KinematicDriver driver(path, kPi / 2, 0.02, false);
  const BedContext bed{&mesh, 0.1, 0.3, 1e-5};
  const PassStart start = driver.BeginPass(2, bed);
  const double h = 0.07, z0 = 0.1 - 0.04 + h, lift = 0.3 - 0.06, descent = lift / 0.1;
  EXPECT_NEAR(start.duration, descent + 1.0, kTol);
  EXPECT_NEAR(driver.PlannedDuration(2, bed), start.duration, 0.0);
  EXPECT_FALSE(start.start_buried);
  const dem::Quat level{0, 1, 0, 0};
  const dem::Quat heading = dem::AxisAngle({0, 0, 1}, kPi / 2);
  for (double tau : {0.0, 0.5, 1.2, descent - 1e-3, descent, descent + 0.25, descent + 0.999,
                     descent + 1.0, descent + 2.0}) {
    const std::string at = "tau = " + std::to_string(tau);
    const dem::MeshMotion m = driver.MotionAt(tau);
    dem::Vec3 position{0.2, 0.15, z0}, velocity;
    if (tau < descent) {
      position.z += lift - 0.1 * tau;
      velocity = {0, 0, -0.1};
    } else {
      const double s = std::min(tau - descent, 1.0);
      position.y += 0.1 * s;
      if (tau - descent < 1.0) velocity = {0, 0.1, 0};
    }
    ExpectVecNear(m.pose.position, position, kTol, at + " position");
    ExpectVecNear(m.velocity, velocity, kTol, at + " velocity");
    ExpectVecNear(m.angular_velocity, {0, 0, 0}, 0.0, at + " angular velocity");
    const dem::Quat q = heading * level;
    for (const dem::Vec3& e : {dem::Vec3{1, 0, 0}, dem::Vec3{0, 0, 1}})
      ExpectVecNear(dem::Rotate(m.pose.orientation, e), dem::Rotate(q, e), kTol, at + " axes");
  }
  // The pass ends half a step before its planned length (the loop's steps land on it).
  EXPECT_FALSE(driver.PassOver(start.duration - 1e-5));
  EXPECT_TRUE(driver.PassOver(start.duration - 0.4e-5));
}

// scenes/lift_dig.yaml: tiny_dig's pass written as a `moves:` list, then a vertical lift of
// 0.06 m after the tilt. The scoop leaves the bed: at the end its lowest point is above the top
// of every particle of the bed it started on, and it carries its sample out (the cavity holds
// particles when the pass ends).
TEST(KinematicDriverTest, LiftAfterTheTiltLeavesTheBedCarryingMaterial) {
  const Scene scene = LoadScene(std::string(SCOOPSIM_SOURCE_DIR) + "/scenes/lift_dig.yaml");
  ASSERT_EQ(scene.dig.trajectory.moves.size(), 5u);
  World world(scene, 2);
  SettleReport report;
  ASSERT_EQ(world.Pour(true, &report), kExitOk);
  double bed_top = 0;
  const dem::Particles& p = world.system().particles();
  for (size_t i = 0; i < p.size(); ++i) bed_top = std::max(bed_top, p.x[i].z + p.radius[i]);
  world.StartDig(KinematicDriver::ForDig(scene.dig));
  RunControl control;
  control.quiet = true;
  ASSERT_EQ(world.Run(control).exit_status, kExitOk);
  const dem::System& system = world.system();
  const dem::Pose& pose = system.mesh_motion(0).pose;
  double lowest = 1e300;
  for (const dem::Vec3& v : system.mesh(0).vertices) lowest = std::min(lowest, dem::Apply(pose, v).z);
  EXPECT_GT(lowest, bed_top) << "the scoop is still in the bed";
  ASSERT_EQ(world.dig_summary().collected_mass.size(), 1u);
  // At least 20 particles of 8 mm snow (0.64 g each at 300 kg/m^3) are carried out.
  EXPECT_GT(world.dig_summary().collected_mass[0], 20 * 300 * 4.0 / 3.0 * kPi * std::pow(8e-3, 3));
}

}  // namespace
}  // namespace sim

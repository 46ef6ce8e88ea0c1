// A settled bed of 3.5 mm snow spheres (scenes/settle_small.yaml) against the properties of a
// granular packing at rest.
#include "sim/loop/bed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "sim/input/scene.h"
#include "tests/cli_util.h"

namespace sim {
namespace {

// ctest runs every TEST in a process of its own, so one test settles the bed once and makes all
// the checks on it.
struct Bed {
  Scene* scene_;
  dem::System* system_;
  SettleReport report_;
  void Settles();
  void SolidFractionBetweenLooseAndClosePacking();
  void OverlapsSmall();
  void WallsCarryTheWeight();
};

TEST(SettledBedTest, SnowBedAtRest) {
  Scene scene = LoadScene(std::string(SCOOPSIM_SOURCE_DIR) + "/scenes/settle_small.yaml");
  dem::System system(scene.materials, MakeSystemConfig(scene));
  system.set_num_threads(2);
  Bed bed{&scene, &system, FillAndSettle(scene, &system, nullptr)};
  bed.Settles();
  bed.SolidFractionBetweenLooseAndClosePacking();
  bed.OverlapsSmall();
  bed.WallsCarryTheWeight();
}

void Bed::Settles() {
  ASSERT_TRUE(report_.status.ok()) << report_.status.message;
  EXPECT_TRUE(report_.settled) << "mean KE " << report_.mean_ke << " J after " << report_.sim_time;
  EXPECT_EQ(static_cast<int64_t>(system_->particles().size()), scene_->bed.count);
}

// Solid fraction of a random packing of frictional monodisperse spheres: between random loose
// and random close (~0.64) packing. Spheres that roll freely pack no looser than ~0.55; rolling
// resistance (here EDEM's model, mu_r 0.05, which brakes every spin) lets a poured packing stay
// looser than that (Santos et al. 2020, "Granular packings with sliding, rolling, and twisting
// friction", Phys. Rev. E 102, 032903): bounds 0.50 and 0.64. Measured in the interior (two
// diameters from the side walls and the floor, three below the surface), counting the spheres whose
// centre lies inside.
void Bed::SolidFractionBetweenLooseAndClosePacking() {
  const dem::Particles& p = system_->particles();
  const double d = 2 * scene_->bed.radius_max;
  std::vector<double> z;
  for (const dem::Vec3& x : p.x) z.push_back(x.z);
  std::sort(z.begin(), z.end());
  const double top = z[z.size() * 98 / 100];  // ignore a few loose spheres on the surface
  const dem::Vec3 lo{scene_->box_min.x + 2 * d, scene_->box_min.y + 2 * d, 2 * d};
  const dem::Vec3 hi{scene_->box_max.x - 2 * d, scene_->box_max.y - 2 * d, top - 3 * d};
  ASSERT_GT(hi.z - lo.z, 3 * d);
  double volume = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const dem::Vec3& x = p.x[i];
    if (x.x > lo.x && x.x < hi.x && x.y > lo.y && x.y < hi.y && x.z > lo.z && x.z < hi.z)
      volume += 4.0 / 3.0 * M_PI * std::pow(p.radius[i], 3);
  }
  const double fraction = volume / ((hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z));
  EXPECT_GT(fraction, 0.50);
  EXPECT_LT(fraction, 0.64);
}

// Largest overlap below 0.5% of the diameter (brute force over all pairs and walls).
void Bed::OverlapsSmall() {
  const dem::Particles& p = system_->particles();
  double worst = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    for (size_t j = i + 1; j < p.size(); ++j)
      worst = std::max(worst, (p.radius[i] + p.radius[j] - dem::Norm(p.x[i] - p.x[j])) /
                                  (2 * std::min(p.radius[i], p.radius[j])));
    for (const dem::Plane& pl : system_->config().planes)
      worst = std::max(worst,
                       (p.radius[i] - dem::Dot(p.x[i] - pl.point, pl.normal)) / (2 * p.radius[i]));
  }
  EXPECT_LT(worst, 0.005);
  EXPECT_GT(worst, 0.0) << "a bed at rest has contacts";
}

// Static equilibrium: the vertical forces on all walls together carry the bed's weight (within 1%,
// averaged over 200 steps); the floor alone carries less because the side walls hold part of the
// weight by friction (Janssen 1895).
void Bed::WallsCarryTheWeight() {
  const dem::Particles& p = system_->particles();
  double weight = 0;
  for (size_t i = 0; i < p.size(); ++i) weight += p.mass[i] * -scene_->gravity.z;
  double all = 0, floor = 0;
  const int steps = 200;
  for (int k = 0; k < steps; ++k) {
    const dem::StepStatus st = system_->Step();
    ASSERT_TRUE(st.ok()) << st.message;
    for (size_t w = 0; w < system_->config().planes.size(); ++w)
      all += -system_->plane_force(static_cast<int>(w)).z / steps;
    floor += -system_->plane_force(0).z / steps;
  }
  EXPECT_NEAR(all, weight, 0.01 * weight);
  EXPECT_LT(floor, 0.99 * weight) << "side walls carry part of the weight (Janssen)";
}

// A bed of 200 four-sphere tetrahedra (paper Table 6 ice, Earth gravity so it settles in 0.4 s)
// poured at random orientations and settled: every clump ends slower than 1 mm/s, and the walls
// carry the clumps' weight (sum of m g, within 1%, averaged over 200 steps): gravity acts on each
// clump once, at its centre of mass.
TEST(SettledBedTest, ClumpBedOfTetrahedraAtRest) {
  const std::filesystem::path dir = scoopsim_test::ProcessTempDir("bed_test");
  const std::string path = (dir / "clumps.yaml").string();
  std::ofstream(path) << "materials: " << SCOOPSIM_SOURCE_DIR << "/scenes/materials.yaml\n"
                      << R"(gravity: [0, 0, -9.81]
time_step: {rayleigh_fraction: 0.25}
box: {min: [0, 0, 0], max: [0.035, 0.035, 0.08], wall_material: wall}
bed:
  material: ice
  clump: tetra4
  count: 200
  seed: 2
  fill_fraction: 0.3
  settle: {kinetic_energy: 1.0e-13, max_time: 1.5}
)";
  const Scene scene = LoadScene(path);
  std::filesystem::remove_all(dir);
  dem::System system(scene.materials, MakeSystemConfig(scene));
  system.set_num_threads(2);
  const SettleReport report = FillAndSettle(scene, &system, nullptr);
  ASSERT_TRUE(report.status.ok()) << report.status.message;
  EXPECT_TRUE(report.settled) << "mean KE " << report.mean_ke << " J after " << report.sim_time;
  const dem::Clumps& c = system.clumps();
  ASSERT_EQ(static_cast<int64_t>(c.size()), scene.bed.count);
  EXPECT_EQ(system.num_bodies(), scene.bed.count);
  EXPECT_EQ(system.particles().size(), 4u * c.size());
  double fastest = 0, weight = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    fastest = std::max(fastest, dem::Norm(c.v[k]));
    weight += c.mass[k] * -scene.gravity.z;
  }
  EXPECT_LT(fastest, 1e-3) << "m/s";
  double all = 0;
  const int steps = 200;
  for (int k = 0; k < steps; ++k) {
    const dem::StepStatus st = system.Step();
    ASSERT_TRUE(st.ok()) << st.message;
    for (size_t w = 0; w < system.config().planes.size(); ++w)
      all += -system.plane_force(static_cast<int>(w)).z / steps;
  }
  EXPECT_NEAR(all, weight, 0.01 * weight);
}

}  // namespace
}  // namespace sim

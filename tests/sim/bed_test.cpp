// A settled bed of 3.5 mm snow spheres (scenes/settle_small.yaml) against the properties of a
// granular packing at rest.
#include "sim/bed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sim/scene.h"

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
// (~0.55) and random close (~0.64) packing. Measured in the interior (two diameters from the side
// walls and the floor, three below the surface), counting the spheres whose centre lies inside.
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
  EXPECT_GT(fraction, 0.55);
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

}  // namespace
}  // namespace sim

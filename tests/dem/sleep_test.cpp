// Sleeping particles (dem SleepConfig): a resting layer falls asleep and stays exactly at rest;
// an impact wakes the particles it touches and no others; a mesh approaching wakes the particles
// of its zone; results do not depend on the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "tests/dem/test_util.h"

namespace dem {
namespace {

constexpr double kRadius = 1.75e-3;

SystemConfig LayerConfig() {
  SystemConfig c;
  c.gravity = {0, 0, -9.81};
  c.time_step = 0.1 * RayleighTimeStep(kRadius, test::Snow());
  c.skin = 0.5 * kRadius;
  c.domain_min = {0, 0, 0};
  c.domain_max = {0.1, 0.1, 0.1};
  c.planes = {test::Floor(0.0, 1)};
  c.sleep.enabled = true;
  c.sleep.check_every = 10;
  c.sleep.quiet_checks = 3;
  c.sleep.wake_distance = 0.005;
  c.sleep.wake_margin = 0.005;
  return c;
}

// A 20 x 20 layer of spheres on the floor, 0.2 r apart: each rests on the floor alone.
void AddLayer(System& s) {
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i)
      s.AddParticle({0.01 + i * 2.2 * kRadius, 0.01 + j * 2.2 * kRadius, kRadius * 0.9999}, {}, {},
                    kRadius, 0);
}

TEST(SleepTest, RestingLayerSleepsAndImpactWakesOnlyWhatItTouches) {
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), LayerConfig());
  s.set_num_threads(1);
  AddLayer(s);
  test::StepOk(s, 2000);
  EXPECT_EQ(s.awake_count(), 0);  // all quiet: asleep
  const Particles before = s.particles();
  // Drop a sphere at 0.5 m/s onto particle (5, 5) (id 105).
  const Vec3 target =
      before.x[0] * 0.0 + Vec3{0.01 + 5 * 2.2 * kRadius, 0.01 + 5 * 2.2 * kRadius, kRadius};
  s.AddParticle(target + Vec3{0, 0, 2 * kRadius + 1e-4}, {0, 0, -0.5}, {}, kRadius, 0);
  test::StepOk(s, 200);
  const Particles& p = s.particles();
  int64_t moved = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.id[i] == 400) continue;  // the dropped sphere
    const bool hit = p.id[i] == 105;
    // The struck sphere woke and moved; every other sphere is bitwise where it slept.
    for (size_t b = 0; b < before.size(); ++b)
      if (before.id[b] == p.id[i]) {
        const bool same =
            p.x[i].x == before.x[b].x && p.x[i].y == before.x[b].y && p.x[i].z == before.x[b].z;
        if (!same) ++moved;
        if (hit) {
          EXPECT_FALSE(same);
        }
      }
  }
  EXPECT_GE(moved, 1);
  EXPECT_LE(moved, 5);  // the struck sphere and at most its four nearest neighbours
}

// A cube mesh lowered towards the sleeping layer wakes the spheres under it (those within
// wake_distance + wake_margin of its surface) and leaves the far ones asleep.
TEST(SleepTest, ApproachingMeshWakesItsZone) {
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), LayerConfig());
  s.set_num_threads(1);
  AddLayer(s);
  const double h = 0.004;
  const TriangleMesh cube = test::Cube(h, 1);
  const int k = s.AddMesh(cube);
  MeshMotion mm;
  mm.pose.position = {0.03, 0.03, 0.08};  // far above
  s.SetMeshMotion(k, mm);
  test::StepOk(s, 2000);
  EXPECT_EQ(s.awake_count(), 0);
  mm.pose.position.z = h + 2 * kRadius + 0.002;  // 2 mm above the spheres: in the inner zone
  s.SetMeshMotion(k, mm);
  test::StepOk(s, 20);
  // Awake: the spheres whose centres lie within the outer zone, 10 mm of the cube's surface:
  // distance to an axis-aligned cube = |max(|p - c| - h, 0)| per axis (closed form).
  int64_t expected = 0;
  const Particles& p = s.particles();
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 d = p.x[i] - mm.pose.position;
    const Vec3 out{std::max(std::abs(d.x) - h, 0.0), std::max(std::abs(d.y) - h, 0.0),
                   std::max(std::abs(d.z) - h, 0.0)};
    if (Norm(out) < 0.01) ++expected;
  }
  EXPECT_GT(expected, 0);
  EXPECT_EQ(s.awake_count(), expected);
}

// The phase clock (System::phase_times): each phase's share is a part of the wall time around
// the steps (their sum cannot exceed it), and a phase whose work did not happen stays at zero:
// no mesh, no mesh time; with a mesh near the layer, some. Pairs and integration always run.
TEST(SleepTest, PhaseTimesAddUpToNoMoreThanTheWallTime) {
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), LayerConfig());
  s.set_num_threads(1);
  AddLayer(s);
  const auto t0 = std::chrono::steady_clock::now();
  test::StepOk(s, 300);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PhaseTimes p = s.phase_times();
  EXPECT_GT(p.pairs, 0.0);
  EXPECT_GT(p.integrate, 0.0);
  EXPECT_GT(p.rebuild, 0.0);  // the first step builds the list
  EXPECT_GT(p.sleep, 0.0);    // checks every 10 steps
  EXPECT_EQ(p.mesh, 0.0);
  EXPECT_LE(p.Total(), wall);
  const int k = s.AddMesh(test::Cube(0.004, 1));
  MeshMotion mm;
  mm.pose.position = {0.03, 0.03, 0.004 + 3 * kRadius};
  s.SetMeshMotion(k, mm);
  test::StepOk(s, 20);
  EXPECT_GT(s.phase_times().mesh, 0.0);
}

// Contact history survives sleep, and waking needs no neighbour-list rebuild. Rows of touching
// spheres (along x) are set sliding sideways in alternate directions, so that their mutual and
// floor contacts store tangential springs when friction stops them; once all sleep, a cube lowered
// into the wake zone (not touching) wakes them. A woken sphere starts at rest (v = 0, f = 0), so
// its first step adds v_rel dt = 0 to every spring: the records must come back as they were put
// to sleep (relative 1e-12), and the build count must not change across the wake.
TEST(SleepTest, WakingKeepsContactHistoryAndCostsNoRebuild) {
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), LayerConfig());
  s.set_num_threads(1);
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < 10; ++i)
      s.AddParticle({0.01 + i * 1.9998 * kRadius, 0.01 + j * 2.2 * kRadius, kRadius * 0.9999},
                    {0, (i % 2 ? 2e-3 : -2e-3), 0}, {}, kRadius, 0);
  const double h = 0.03;
  const int k = s.AddMesh(test::Cube(h, 1));
  MeshMotion mm;
  mm.pose.position = {0.03, 0.03, 0.09};  // far above the layer
  s.SetMeshMotion(k, mm);
  test::StepOk(s, 4000);
  ASSERT_EQ(s.awake_count(), 0);
  const std::vector<ContactRecord> before = s.Contacts();
  int64_t pairs_with_history = 0, walls_with_history = 0;
  for (const ContactRecord& c : before) (c.b >= 0 ? pairs_with_history : walls_with_history) += 1;
  ASSERT_GT(pairs_with_history, 0) << "the set-up must leave springs between sleepers";
  ASSERT_GT(walls_with_history, 0) << "and between sleepers and the floor";
  const int64_t builds = s.neighbor_stats().builds;
  // The cube's bottom 4 mm above the centres (inner zone: wake_distance 5 mm), 2.25 mm above the
  // tops of the spheres.
  mm.pose.position.z = kRadius + 0.004 + h;
  s.SetMeshMotion(k, mm);
  int steps = 0;
  while (s.awake_count() == 0 && steps < 20) {
    test::StepOk(s, 1);
    ++steps;
  }
  ASSERT_EQ(s.awake_count(), 100);
  test::StepOk(s, 1);
  EXPECT_EQ(s.neighbor_stats().builds, builds);
  EXPECT_EQ(s.mesh_wrench(k).contacts, 0);
  const std::vector<ContactRecord> after = s.Contacts();
  ASSERT_EQ(after.size(), before.size());
  for (size_t c = 0; c < before.size(); ++c) {
    EXPECT_EQ(after[c].a, before[c].a);
    EXPECT_EQ(after[c].b, before[c].b);
    EXPECT_LE(Norm(after[c].shear - before[c].shear), 1e-12 * Norm(before[c].shear))
        << "contact " << before[c].a << "-" << before[c].b;
  }
}

// Determinism with sleeping and a moving mesh: spheres rained onto a sleeping layer while a cube
// ploughs through it; 1 and 2 threads give the same hash.
struct RainResult {
  uint64_t hash = 0;
  NeighborStats stats;
};
RainResult Rain(int threads, double near_fraction, bool sleeping) {
  SystemConfig config = LayerConfig();
  config.near_fraction = near_fraction;
  config.sleep.enabled = sleeping;
  System s(test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05}), config);
  s.set_num_threads(threads);
  AddLayer(s);
  for (int k = 0; k < 30; ++k)
    s.AddParticle({0.012 + 0.0013 * k, 0.02 + 0.0009 * k, 0.01 + 0.004 * (k % 5)}, {0, 0, -0.3}, {},
                  kRadius, 0);
  const double h = 0.003;
  const TriangleMesh cube = test::Cube(h, 1);
  const int mesh = s.AddMesh(cube);
  int64_t touched = 0;
  const double dt = s.config().time_step, u = 1.0;  // 1 cm in the run: through two columns
  for (int k = 0; k < 3000; ++k) {
    MeshMotion mm;
    mm.pose.position = {-0.002 + u * (k + 1) * dt, 0.03, kRadius + h * 0.5};
    mm.pose.orientation = AxisAngle({0, 0, 1}, 0.3);
    mm.velocity = {u, 0, 0};
    s.SetMeshMotion(mesh, mm);
    const StepStatus st = s.Step();
    if (!st.ok()) {
      ADD_FAILURE() << st.message;
      break;
    }
    touched = std::max(touched, s.mesh_wrench(mesh).contacts);
  }
  EXPECT_GT(touched, 0);  // the cube did plough into the layer
  return {s.StateHash(), s.neighbor_stats()};
}
uint64_t RainHash(int threads) { return Rain(threads, SystemConfig{}.near_fraction, true).hash; }

TEST(SleepTest, SameResultForOneAndTwoThreads) { EXPECT_EQ(RainHash(1), RainHash(2)); }

// The near list (SystemConfig::near_fraction) only skips pairs that cannot touch yet: the same
// rain and plough, awake or sleeping, end in exactly the state (bit for bit) of a force pass that
// scans every pair of the Verlet list (a near fraction so large that every pair is near).
TEST(NearListTest, SameStateAsScanningTheWholeList) {
  for (const bool sleeping : {false, true}) {
    SCOPED_TRACE(sleeping ? "sleeping" : "awake");
    const RainResult near = Rain(2, 0.1, sleeping);
    const RainResult whole = Rain(2, 1e6, sleeping);
    EXPECT_EQ(near.hash, whole.hash);
    EXPECT_EQ(near.stats.builds, whole.stats.builds);
    // The near list was made again many times in the run (1 m/s plough, 0.3 m/s rain) and
    // holds fewer pairs than the whole list.
    EXPECT_GT(near.stats.near_builds, 20);
    EXPECT_LT(near.stats.near_pairs, whole.stats.near_pairs);
    // (with sleeping the near list covers only the particles the force pass visits)
    if (sleeping) {
      EXPECT_LT(whole.stats.near_pairs, whole.stats.pairs);
    } else {
      EXPECT_EQ(whole.stats.near_pairs, whole.stats.pairs);
    }
  }
}

// A part of the neighbour list made again (SystemConfig::partial_rebuild, RebuildPart in
// dem/neighbor_build.cpp) against the whole: a long sleeping layer (no gravity, no floor) that two
// cubes plough across, far apart. Only the slabs the moved particles were in or went to are
// sorted and listed again, and the claim is that this is exactly the full build: the same
// storage order, pairs and history, so the same state to the bit (StateHash), on one and two
// threads, and through a SaveState / RestoreState half way (the restored list has no scratch).
struct PloughResult {
  uint64_t hash = 0;
  NeighborStats stats;
};
PloughResult Plough(int threads, bool partial, bool restore_half_way, bool dimers = false,
                    double flyer_speed = 0) {
  SystemConfig config = LayerConfig();
  config.domain_min = {-0.04, -0.04, -0.01};
  config.domain_max = {0.32, 0.09, flyer_speed != 0 ? 0.2 : 0.02};
  config.gravity = {0, 0, 0};
  config.planes.clear();
  config.partial_rebuild = partial;
  const auto materials = test::SnowAndSteel({0.5, 0.5, 0.05}, {0.5, 0.5, 0.05});
  auto s = std::make_unique<System>(materials, config);
  s->set_num_threads(threads);
  // The layer: spheres, or rigid dimers (two spheres 1.2 r apart across the plough's path).
  const int dimer =
      dimers ? s->AddClumpTemplate(
                   {"dimer", {{0, -0.6 * kRadius, 0}, {0, 0.6 * kRadius, 0}}, {kRadius, kRadius}})
             : -1;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 70; ++i) {
      const Vec3 at{0.01 + i * 2.2 * kRadius, 0.01 + j * (dimers ? 3.4 : 2.2) * kRadius, kRadius};
      if (dimers) {
        Pose pose;
        pose.position = at;
        s->AddClump(dimer, pose, {}, {}, 0);
      } else {
        s->AddParticle(at, {}, {}, kRadius, 0);
      }
    }
  // Two anchors at opposite corners, asleep from the first check on (no gravity, nothing near):
  // they hold the bounding box that the cell grid spans, as a dug bed's sleeping floor and far
  // ends do, so that the grid stays the same from one build to the next.
  s->AddParticle({-0.01, -0.03, -0.005}, {}, {}, kRadius, 0);
  s->AddParticle({0.3, 0.08, 0.01}, {}, {}, kRadius, 0);
  // A particle flying up out of the layer between the cubes, or falling towards it from above:
  // the bounding box's top, so the grid gains (loses) a cell along z every few builds
  // (NeighborList::Regrid).
  if (flyer_speed > 0) s->AddParticle({0.13, 0.02, 0.01}, {0, 0, flyer_speed}, {}, kRadius, 0);
  if (flyer_speed < 0) s->AddParticle({0.13, 0.02, 0.15}, {0, 0, flyer_speed}, {}, kRadius, 0);
  const double h = 0.003;
  const TriangleMesh cube = test::Cube(h, 1);
  const double along[2] = {0.06, 0.2};  // two cubes: two runs of slabs to make again
  int mesh[2] = {s->AddMesh(cube), s->AddMesh(cube)};
  const double dt = s->config().time_step, u = 1.0;
  int64_t touched[2] = {0, 0};
  for (int k = 0; k < 6000; ++k) {
    if (restore_half_way && k == 3000) {
      auto fresh = std::make_unique<System>(materials, config);
      fresh->set_num_threads(threads);
      for (int c = 0; c < 2; ++c) mesh[c] = fresh->AddMesh(cube);
      fresh->RestoreState(s->SaveState());
      s = std::move(fresh);
    }
    for (int c = 0; c < 2; ++c) {
      MeshMotion mm;
      mm.pose.position = {along[c], 0.002 + u * (k + 1) * dt, kRadius + h * 0.5};
      mm.pose.orientation = AxisAngle({0, 0, 1}, 0.3);
      mm.velocity = {0, u, 0};
      s->SetMeshMotion(mesh[c], mm);
    }
    const StepStatus st = s->Step();
    if (!st.ok()) {
      ADD_FAILURE() << st.message;
      break;
    }
    for (int c = 0; c < 2; ++c) touched[c] = std::max(touched[c], s->mesh_wrench(mesh[c]).contacts);
  }
  EXPECT_GT(touched[0], 0);  // each cube did plough into the layer
  EXPECT_GT(touched[1], 0);
  return {s->StateHash(), s->neighbor_stats()};
}

TEST(PartialRebuildTest, SameStateAsTheFullBuild) {
  const PloughResult full = Plough(1, false, false);
  EXPECT_EQ(full.stats.partial_builds, 0);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const PloughResult part = Plough(threads, true, false);
    EXPECT_EQ(part.hash, full.hash);
    EXPECT_EQ(part.stats.builds, full.stats.builds);
    // Most builds were partial (not the first, which sets the grid up).
    EXPECT_GT(part.stats.partial_builds, part.stats.builds / 2);
    EXPECT_LT(part.stats.partial_builds, part.stats.builds);
  }
  const PloughResult resumed = Plough(2, true, true);
  EXPECT_EQ(resumed.hash, full.hash);
  EXPECT_GT(resumed.stats.partial_builds, 0);  // (counted since the restore)
}

// The same while the grid changes: a particle flies up out of the layer, so the bounding box's
// top rises and the grid gains a cell along its third axis every few builds, with the same
// slabs. The partial build goes on from the new grid's keys (the full build's order, as the
// unmoved slabs' keys still ascend) instead of building everything.
TEST(PartialRebuildTest, SameStateWhileTheGridGrows) {
  const PloughResult full = Plough(1, false, false, false, 2.0);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const PloughResult part = Plough(threads, true, false, false, 2.0);
    EXPECT_EQ(part.hash, full.hash);
    EXPECT_EQ(part.stats.builds, full.stats.builds);
    // Full: the first build, the two where the grid's cell cap (4 n + 4096 cells: few spheres
    // here) widens the cells, and one where most of the layer had moved. Without Regrid every
    // build that added a cell was full too: 10 of 89.
    EXPECT_LE(part.stats.builds - part.stats.partial_builds, 4);
  }
}

// And while it shrinks: a particle falls from 0.15 m towards the layer, so the grid's top cells
// merge (the particles of two cells in one, in persistent-id order again).
TEST(PartialRebuildTest, SameStateWhileTheGridShrinks) {
  const PloughResult full = Plough(1, false, false, false, -2.0);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const PloughResult part = Plough(threads, true, false, false, -2.0);
    EXPECT_EQ(part.hash, full.hash);
    EXPECT_EQ(part.stats.builds, full.stats.builds);
    // Full: the first build and two more (the cell cap, most of the layer moved); without
    // Regrid, 6 of 89.
    EXPECT_LE(part.stats.builds - part.stats.partial_builds, 3);
  }
}

// The same with rigid clumps (dem/clump.h), which move their spheres themselves and wake and
// sleep whole: a layer of dimers.
TEST(PartialRebuildTest, ClumpsSameStateAsTheFullBuild) {
  const PloughResult full = Plough(1, false, false, true);
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const PloughResult part = Plough(threads, true, false, true);
    EXPECT_EQ(part.hash, full.hash);
    EXPECT_EQ(part.stats.builds, full.stats.builds);
    EXPECT_GT(part.stats.partial_builds, part.stats.builds / 2);
  }
  const PloughResult resumed = Plough(2, true, true, true);
  EXPECT_EQ(resumed.hash, full.hash);
  EXPECT_GT(resumed.stats.partial_builds, 0);
}

}  // namespace
}  // namespace dem

// The run loop (sim/loop/world.cpp). The golden state hash: scenes/tiny_dig.yaml (a bed of 1450
// snow spheres poured, then one Table 1 pass) ends in the state whose hash is kTinyDigHash, on 1
// and on 2 threads. When physics changes on purpose, update kTinyDigHash in the same commit and
// say why there; any other change of it is a regression.
// Determinism of a whole run through the CLI (scoopsim run): the same scene gives the same root
// state_hash attribute with 1 and 2 threads, and in two runs; a run from a saved bed equals a run
// that made the bed itself.
#include "sim/loop/world.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/input/exit_status.h"
#include "sim/input/scene.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("determinism");
  return dir;
}

// 600 snow spheres in a 3 cm box: poured, settled for the layer's fall time, then 0.01 s run.
// With `clumps`: 50 ice clumps of 4 overlapping spheres (tetra4) instead.
std::string WriteScene(const std::string& name, const std::string& bed_file, bool clumps = false) {
  const fs::path path = TempDir() / name;
  std::ofstream(path) << "materials: " << kSourceDir << "/scenes/materials.yaml\n"
                      << R"(gravity: [0, 0, -1.3]
time_step: {rayleigh_fraction: 0.2}
box: {min: [0, 0, 0], max: [0.03, 0.03, 0.06], wall_material: wall}
bed:
)"
                      << (clumps ? "  material: ice\n  clump: tetra4\n  count: 50\n"
                                 : "  material: snow\n  radius: [1.5e-3, 2.0e-3]\n  count: 600\n")
                      << R"(  seed: 7
  settle: {kinetic_energy: 1.0, max_time: 1.0}
)" << (bed_file.empty() ? "" : "  file: " + bed_file + "\n")
                      << "duration: 0.01\n";
  return path.string();
}

int Scoopsim(const std::string& args) { return scoopsim_test::RunScoopsim(args + " --quiet"); }

uint64_t StateHash(const std::string& h5) {
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << h5;
  const hid_t attr = H5Aopen(file, "state_hash_u64", H5P_DEFAULT);
  uint64_t hash = 0;
  EXPECT_GE(H5Aread(attr, H5T_NATIVE_UINT64, &hash), 0);
  H5Aclose(attr);
  H5Fclose(file);
  return hash;
}

// History of kTinyDigHash (newest first):
//   3480ffbd08eaa986  2026-12-03  issue 18: the edem pair kernel takes each particle's 1/|w|,
//                                 made once a step (the same law, other rounding).
//   df724007ea818c7c  2026-12-02  issue 18: the contact law's defaults became the study's code's
//                                 (EDEM's rolling friction, the standard damping formula).
//   832715449e8ff685  2026-12-02  snow digs at 0.3 t_R kept tiny_dig at 0.25 t_R; value of record
//                                 when the run loop became sim::World (no physics change).
constexpr uint64_t kTinyDigHash = 0x3480ffbd08eaa986ull;

// The contact law before issue 18 (rolling_model legacy, damping exact_restitution on every pair)
// still gives that run's hash: old results can be reproduced bit for bit.
constexpr uint64_t kTinyDigLegacyLawHash = 0x832715449e8ff685ull;

uint64_t TinyDigHash(int threads, bool legacy_law = false) {
  sim::Scene scene = sim::LoadScene(kSourceDir + "/scenes/tiny_dig.yaml");
  if (legacy_law) {
    dem::MaterialTable& t = scene.materials;
    for (int a = 0; a < t.size(); ++a) {
      for (int b = a; b < t.size(); ++b) {
        if (!t.has_interaction(a, b)) continue;
        dem::Interaction in = t.interaction(a, b);
        in.rolling_model = dem::RollingModel::kLegacy;
        in.damping = dem::DampingLaw::kExactRestitution;
        t.SetInteraction(a, b, in);
      }
    }
  }
  sim::World world(scene, threads);
  sim::SettleReport report;
  EXPECT_EQ(world.Pour(true, &report), sim::kExitOk);
  world.StartDig(sim::KinematicDriver::ForDig(scene.dig));
  sim::RunControl control;
  control.quiet = true;
  EXPECT_EQ(world.Run(control).exit_status, sim::kExitOk);
  EXPECT_TRUE(world.Done());
  return world.system().StateHash();
}

TEST(WorldTest, GoldenStateHashOnOneAndTwoThreads) {
  for (const int threads : {1, 2}) {
    EXPECT_EQ(TinyDigHash(threads), kTinyDigHash)
        << threads
        << " thread(s): the physics changed; "
           "if on purpose, update kTinyDigHash and say why";
  }
}

TEST(WorldTest, LegacyContactLawReproducesTheHashBeforeIssue18) {
  EXPECT_EQ(TinyDigHash(2, true), kTinyDigLegacyLawHash);
}

TEST(RunDeterminismTest, RunStateHashIndependentOfThreadsAndRepeatable) {
  for (const bool clumps : {false, true}) {
    SCOPED_TRACE(clumps ? "clumps" : "spheres");
    const std::string scene = WriteScene(clumps ? "pour_c.yaml" : "pour.yaml", "", clumps);
    const std::string out = (TempDir() / (clumps ? "tc" : "t")).string();
    ASSERT_EQ(Scoopsim("run " + scene + " -o " + out + "1.h5 --threads 1"), 0);
    // One 2-thread run exactly so, one with the thread governor free to use fewer.
    ASSERT_EQ(Scoopsim("run " + scene + " -o " + out + "2.h5 --threads 2 --fixed-threads"), 0);
    ASSERT_EQ(Scoopsim("run " + scene + " -o " + out + "3.h5 --threads 2"), 0);
    const uint64_t h1 = StateHash(out + "1.h5");
    EXPECT_EQ(h1, StateHash(out + "2.h5")) << "1 thread vs 2 threads";
    EXPECT_EQ(h1, StateHash(out + "3.h5")) << "two runs";
  }
}

// `scoopsim bed` then `run` from the saved bed replays the run that poured its own bed, bit for
// bit: the bed file keeps positions, velocities, last forces and contact history, and both
// runs rebuild their neighbour lists at the same state. The scene names the bed by a path
// relative to its own folder.
// The same with a bed of clumps: the bed file keeps the clumps' state (CoM, orientation,
// velocities, angular momentum, last force and torque) and their spheres.
TEST(RunDeterminismTest, RunFromSavedBedEqualsRunThatPouredIt) {
  for (const bool clumps : {false, true}) {
    SCOPED_TRACE(clumps ? "clumps" : "spheres");
    const std::string tag = clumps ? "_c" : "";
    const std::string pour = WriteScene("pour_b" + tag + ".yaml", "", clumps);
    const std::string bed = (TempDir() / ("bed" + tag + ".h5")).string();
    ASSERT_EQ(Scoopsim("bed " + pour + " -o " + bed + " --threads 2"), 0);
    // Named relative to the scene's folder, as scenes/paper/*.yaml name their beds.
    WriteScene("from_bed" + tag + ".yaml", "bed" + tag + ".h5", clumps);
    const std::string out = (TempDir() / ("r" + tag)).string();
    ASSERT_EQ(Scoopsim("run " + pour + " -o " + out + "1.h5 --threads 2"), 0);
    // Run from the folder above the scene's, naming the scene relatively: a relative bed.file
    // must resolve against the scene's folder exactly once.
    const std::string cmd = "cd " + TempDir().parent_path().string() + " && " + SCOOPSIM_BINARY +
                            " run " + TempDir().filename().string() + "/from_bed" + tag +
                            ".yaml -o " + out + "2.h5 --threads 1 --quiet 2>/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    EXPECT_EQ(StateHash(out + "1.h5"), StateHash(out + "2.h5"));
  }
}

// `run --stop-after T` stops T simulated seconds into the run, the output closed as at the
// scene's end (exit status 0; its time attribute is the bed's time plus T, to within a step),
// and `bench step` times the same saved bed: one JSON line, the same state with 1 and 2 threads.
double RootTime(const std::string& h5) {
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << h5;
  const hid_t attr = H5Aopen(file, "time", H5P_DEFAULT);
  double t = -1;
  EXPECT_GE(H5Aread(attr, H5T_NATIVE_DOUBLE, &t), 0);
  H5Aclose(attr);
  H5Fclose(file);
  return t;
}

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(RunDeterminismTest, StopAfterAndBenchStepOnASavedBed) {
  const std::string pour = WriteScene("pour_s.yaml", "");
  const std::string bed = (TempDir() / "bed_s.h5").string();
  ASSERT_EQ(Scoopsim("bed " + pour + " -o " + bed + " --threads 2"), 0);
  const std::string scene = WriteScene("from_bed_s.yaml", bed);
  const std::string whole = (TempDir() / "whole.h5").string();
  const std::string part = (TempDir() / "part.h5").string();
  ASSERT_EQ(Scoopsim("run " + scene + " -o " + whole + " --threads 2"), 0);
  ASSERT_EQ(Scoopsim("run " + scene + " -o " + part + " --threads 2 --stop-after 0.004"), 0);
  const double t_bed = RootTime(whole) - 0.01;  // the scene runs 0.01 s
  // The step of this bed (0.2 t_R of 1.5 mm snow spheres) is under 10 us.
  EXPECT_NEAR(RootTime(part) - t_bed, 0.004, 1e-5);

  std::string json[2];
  for (int threads : {1, 2}) {
    const fs::path out = TempDir() / ("step_" + std::to_string(threads) + ".json");
    // 2000 steps run past the scene's 0.01 s: bench step times steps, whatever the duration.
    ASSERT_EQ(
        scoopsim_test::RunScoopsim("bench step " + scene + " --warm 5 --steps 2000 --threads " +
                                   std::to_string(threads) + " > " + out.string()),
        0);
    json[threads - 1] = ReadAll(out);
    EXPECT_NE(json[threads - 1].find("\"bench\":\"step\",\"particles\":600,"), std::string::npos)
        << json[threads - 1];
    // Every particle is integrated every step (the scene does not sleep).
    EXPECT_NE(json[threads - 1].find("\"awake_per_step\":600,"), std::string::npos)
        << json[threads - 1];
    EXPECT_NE(json[threads - 1].find("\"steps\":2000,"), std::string::npos) << json[threads - 1];
  }
  auto hash = [](const std::string& j) { return j.substr(j.find("state_hash")); };
  EXPECT_EQ(hash(json[0]), hash(json[1]));
  // --arm steps the lander's arm beside the bed: its time apart, the bed's state untouched.
  const fs::path out = TempDir() / "step_arm.json";
  ASSERT_EQ(scoopsim_test::RunScoopsim("bench step " + scene +
                                       " --warm 5 --steps 2000 --threads 1 --arm " + kSourceDir +
                                       "/assets/lander_arm.urdf > " + out.string()),
            0);
  const std::string with_arm = ReadAll(out);
  EXPECT_NE(with_arm.find("\"arm_ms_per_step\":"), std::string::npos) << with_arm;
  EXPECT_EQ(hash(with_arm), hash(json[0]));
}

}  // namespace

// Determinism of a whole run through the CLI (scoopsim run): the same scene gives the same root
// state_hash attribute with 1 and 2 threads, and in two runs; a run from a saved bed equals a run
// that made the bed itself.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

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

TEST(RunDeterminismTest, RunStateHashIndependentOfThreadsAndRepeatable) {
  for (const bool clumps : {false, true}) {
    SCOPED_TRACE(clumps ? "clumps" : "spheres");
    const std::string scene = WriteScene(clumps ? "pour_c.yaml" : "pour.yaml", "", clumps);
    const std::string out = (TempDir() / (clumps ? "tc" : "t")).string();
    ASSERT_EQ(Scoopsim("run " + scene + " -o " + out + "1.h5 --threads 1"), 0);
    ASSERT_EQ(Scoopsim("run " + scene + " -o " + out + "2.h5 --threads 2"), 0);
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

}  // namespace

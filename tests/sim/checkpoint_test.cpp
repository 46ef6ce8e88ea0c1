// Checkpoint and resume (sim/files/checkpoint.h, World::MakeCheckpoint / ResumeFrom) end to end
// through the binary: a run with --checkpoint-every, SIGKILLed once a checkpoint exists and
// resumed with --resume, writes the same output, bit for bit (every dataset, the state hash, every
// root attribute), as the uninterrupted run, for a plain run, a two-pass dig and a bed of clumps,
// on 1 and 2 threads.
// A checkpoint of another scene text or format version is refused with one line, exit 2.
#include "sim/files/checkpoint.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "sim/files/saved_run.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
using scoopsim_test::ReadText;
using scoopsim_test::Wait;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("checkpoint");
  return dir;
}

// The body of each scene (materials, box, step); the kinds below add bed, dig or duration.
std::string Common() {
  const std::string source = SCOOPSIM_SOURCE_DIR;
  return "materials: " + source + "/scenes/materials.yaml\n" + R"(gravity: [0, 0, -1.3]
time_step: {rayleigh_fraction: 0.25}
box: {min: [0, 0, 0], max: [0.37, 0.17, 0.2], wall_material: wall}
sleep: {enabled: true}
health: {max_overlap: 0.35}
output: {interval: 1.0e-3, snapshot_every: 1000, flush_seconds: 0.05}
)";
}

// tiny_dig's bed of 1450 spheres, made once.
std::string SphereBed() {
  static const std::string bed = [] {
    const fs::path scene = TempDir() / "bed.yaml";
    std::ofstream(scene) << Common() << R"(neighbor: {skin: 4.0e-3}
bed: {material: snow, radius: 8.0e-3, count: 1450, seed: 3, fill_fraction: 0.45,
      settle: {kinetic_energy: 1.0e-8, max_time: 1.0}}
)";
    const std::string path = (TempDir() / "bed.h5").string();
    EXPECT_EQ(
        scoopsim_test::RunScoopsim("bed " + scene.string() + " -o " + path + " --threads 2 -q"), 0);
    return path;
  }();
  return bed;
}

std::string WriteScene(const std::string& kind) {
  const std::string source = SCOOPSIM_SOURCE_DIR;
  std::ostringstream s;
  s << Common();
  if (kind == "clumps") {
    // Poured in the run (the checkpoints come after the pour), a loose layer still moving.
    s << R"(bed: {material: ice, clump: tetra4, count: 400, seed: 2, fill_fraction: 0.45,
      settle: {kinetic_energy: 1.0e-3, max_time: 0.05}}
duration: 0.4
)";
  } else {
    s << "neighbor: {skin: 4.0e-3}\n"
      << "bed: {material: snow, radius: 8.0e-3, count: 1450, seed: 3, fill_fraction: 0.45,\n"
      << "      file: " << SphereBed();
    // Weak bonds (issue 44), made when the bed is loaded; the dig breaks some of them.
    if (kind == "bonds") {
      s << ",\n      bonds: {gap: 1.0e-3, modulus: 1.0e6, tensile_strength: 300,\n"
        << "              shear_strength: {cohesion: 300, friction_angle: 20},\n"
        << "              strength_vs_depth: {law: linear, slope: 20}}";
    }
    s << "}\n";
  }
  if (kind == "plain") s << "duration: 2.0\n";
  if (kind == "dig" || kind == "bonds") {
    // Two short passes of a level scoop: down, along, out (blade down, the second pass took the
    // blade 0.4 mm into the box's floor, which the preflight refuses; a plunge of 20 mm and bites
    // of 10 mm pinched a grain between scoop and floor under the edem rolling law, 49% overlap).
    // The mesh relative to the scene's folder, as the shipped scenes give it.
    s << "dig:\n  scoop: {mesh: "
      << fs::path(source + "/assets/scoop.stl").lexically_relative(TempDir()).string()
      << ", material: aluminium}\n"
      << R"(  trajectory:
    preset: none
    start: [0.13, 0.085]
    initial_pitch: 0
    moves:
      - {translate: [0, 0, -1], speed: 0.1, distance: 0.01}
      - {translate: [1, 0, 0], speed: 0.05, distance: 0.03}
      - {translate: [0, 0, 1], speed: 0.2, distance: 0.07}
  passes: 2
  bite_depth: 0.005
  interval: 1.0e-3
)";
  }
  const fs::path path = TempDir() / (kind + ".yaml");
  std::ofstream(path) << s.str();
  return path.string();
}

pid_t Spawn(const std::string& args, const std::string& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(SCOOPSIM_BINARY) + " " + args + " 2>" + log;
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// Every dataset of a file by path, as raw bytes in its native type (H5Ovisit).
std::vector<std::pair<std::string, std::vector<char>>> Datasets(const std::string& path) {
  std::vector<std::pair<std::string, std::vector<char>>> out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return out;
  H5Ovisit(
      file, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t root, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        if (info->type != H5O_TYPE_DATASET) return 0;
        const hid_t d = H5Dopen2(root, name, H5P_DEFAULT);
        const hid_t type = H5Dget_type(d);
        const hid_t native = H5Tget_native_type(type, H5T_DIR_ASCEND);
        const hid_t space = H5Dget_space(d);
        const hssize_t n = H5Sget_simple_extent_npoints(space);
        std::vector<char> bytes(static_cast<size_t>(n) * H5Tget_size(native));
        if (n > 0) H5Dread(d, native, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
        static_cast<std::vector<std::pair<std::string, std::vector<char>>>*>(data)->emplace_back(
            name, std::move(bytes));
        H5Sclose(space);
        H5Tclose(native);
        H5Tclose(type);
        H5Dclose(d);
        return 0;
      },
      &out);
  H5Fclose(file);
  return out;
}

std::string StateHash(const std::string& path) {
  std::string hash;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return hash;
  const hid_t attribute = H5Aopen(file, "state_hash", H5P_DEFAULT);
  if (attribute >= 0) {
    const hid_t type = H5Aget_type(attribute);
    char* text = nullptr;
    if (H5Aread(attribute, type, &text) >= 0 && text != nullptr) hash = text;
    H5free_memory(text);
    H5Tclose(type);
    H5Aclose(attribute);
  }
  H5Fclose(file);
  return hash;
}

// Every root attribute of a file by name, its value as text (numbers to 17 digits).
std::map<std::string, std::string> RootAttributes(const std::string& path) {
  std::map<std::string, std::string> out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return out;
  hsize_t at = 0;
  H5Aiterate2(
      file, H5_INDEX_NAME, H5_ITER_INC, &at,
      [](hid_t root, const char* name, const H5A_info_t*, void* data) -> herr_t {
        const hid_t attribute = H5Aopen(root, name, H5P_DEFAULT);
        const hid_t type = H5Aget_type(attribute);
        std::string value = "?";
        if (H5Tget_class(type) == H5T_STRING) {
          char* text = nullptr;
          if (H5Aread(attribute, type, &text) >= 0 && text != nullptr) value = text;
          H5free_memory(text);
        } else if (H5Tget_class(type) == H5T_INTEGER) {
          unsigned long long v = 0;
          if (H5Aread(attribute, H5T_NATIVE_ULLONG, &v) >= 0) value = std::to_string(v);
        } else {
          double v = 0;
          char text[32];
          if (H5Aread(attribute, H5T_NATIVE_DOUBLE, &v) >= 0) {
            std::snprintf(text, sizeof text, "%.17g", v);
            value = text;
          }
        }
        (*static_cast<std::map<std::string, std::string>*>(data))[name] = value;
        H5Tclose(type);
        H5Aclose(attribute);
        return 0;
      },
      &out);
  H5Fclose(file);
  return out;
}

// Every dataset of `out` equals the reference run's, by name and byte for byte; returns the
// reference's datasets.
std::vector<std::pair<std::string, std::vector<char>>> ExpectSameDatasets(
    const std::string& reference, const std::string& out) {
  const auto want = Datasets(reference);
  const auto got = Datasets(out);
  EXPECT_GT(want.size(), 10u);
  EXPECT_EQ(got.size(), want.size());
  for (size_t k = 0; k < want.size() && k < got.size(); ++k) {
    EXPECT_EQ(got[k].first, want[k].first);
    EXPECT_TRUE(got[k].second == want[k].second) << want[k].first << " differs";
  }
  return want;
}

class ResumeTest : public ::testing::TestWithParam<std::tuple<std::string, int>> {};

TEST_P(ResumeTest, KilledAndResumedRunEqualsTheUninterrupted) {
  const auto& [kind, threads] = GetParam();
  // Given relative to the working folder, as a user types it (the checkpoint keeps it absolute,
  // so paths the run derives from it, such as the scoop_mesh attribute, must not differ).
  const std::string scene = fs::relative(WriteScene(kind)).string();
  const std::string tag = kind + std::to_string(threads);
  const std::string common = " --threads " + std::to_string(threads) + " -q";
  const std::string reference = (TempDir() / (tag + "_reference.h5")).string();
  const std::string out = (TempDir() / (tag + ".h5")).string();
  const fs::path restart = TempDir() / (tag + ".restart.h5");
  const std::string log = (TempDir() / (tag + ".log")).string();
  ASSERT_EQ(Wait(Spawn("run " + scene + " -o " + reference + common, log)), 0) << ReadText(log);

  // Killed a moment after its second checkpoint (one at the start, then every 0.2 s of wall
  // time; each replaces the file, a new inode).
  const pid_t pid = Spawn("run " + scene + " -o " + out + common + " --checkpoint-every 0.2", log);
  auto inode = [&restart] {
    struct stat st {};
    return ::stat(restart.c_str(), &st) == 0 ? st.st_ino : ino_t{0};
  };
  ino_t first = 0;
  for (int k = 0; k < 120000; ++k) {
    const ino_t now = inode();
    if (first == 0) first = now;
    if (now != 0 && now != first) break;
    if (::waitpid(pid, nullptr, WNOHANG) == pid) FAIL() << "ended before a second checkpoint";
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ::kill(pid, SIGKILL);
  ASSERT_EQ(Wait(pid), 128 + SIGKILL) << "ended before the kill: " << ReadText(log);
  ASSERT_TRUE(fs::exists(restart));

  ASSERT_EQ(Wait(Spawn("run --resume " + out + common, log)), 0) << ReadText(log);
  EXPECT_NE(ReadText(log).find("going on from " + restart.string()), std::string::npos)
      << ReadText(log);
  EXPECT_FALSE(fs::exists(restart)) << "kept after the run ended";
  const auto want = ExpectSameDatasets(reference, out);
  EXPECT_EQ(StateHash(out), StateHash(reference));
  EXPECT_EQ(StateHash(out).size(), 16u);
  // Bonds: the dig broke some (their records are among the datasets compared above).
  if (kind == "bonds") {
    bool broken = false;
    for (const auto& d : want)
      broken = broken || d.first.find("bonds/broken/time") != std::string::npos;
    EXPECT_TRUE(broken) << "no bond broke";
  }
  // Defect: the resumed output's start_time was 0 (a dig) or missing (a plain run); every root
  // attribute is now the uninterrupted run's.
  const auto attributes = RootAttributes(reference);
  EXPECT_EQ(attributes.count("start_time"), 1u);
  EXPECT_EQ(RootAttributes(out), attributes);
}

INSTANTIATE_TEST_SUITE_P(Kinds, ResumeTest,
                         ::testing::Combine(::testing::Values("plain", "dig", "clumps", "bonds"),
                                            ::testing::Values(1, 2)),
                         [](const auto& info) {
                           return std::get<0>(info.param) + "_" +
                                  std::to_string(std::get<1>(info.param)) + "_threads";
                         });

// A run of one pass, stopped in it and resumed with `--set dig.passes=2`, ends as the run planned
// with two passes from the start, bit for bit (every dataset, the state hash, the root attributes:
// the reference is given the same two --set lines, so their scene texts are equal). Oracle: the
// uninterrupted two-pass run. Any other change is still refused (MismatchIsRefused).
TEST(CheckpointTest, ResumedWithMorePassesEqualsTheRunPlannedWithThem) {
  const std::string scene = WriteScene("dig");  // two passes of ~1.05 s each
  const std::string common = " --threads 1 -q";
  const std::string reference = (TempDir() / "passes_reference.h5").string();
  const std::string out = (TempDir() / "passes.h5").string();
  const std::string log = (TempDir() / "passes.log").string();
  ASSERT_EQ(
      scoopsim_test::RunScoopsim(
          "run " + scene + " --set dig.passes=1 --set dig.passes=2 -o " + reference + common, log),
      0)
      << ReadText(log);
  // One pass, checkpointed every 20 ms of wall time, stopped 0.5 s into the dig (mid-pass): the
  // restart file keeps its last checkpoint, somewhere in pass 1.
  ASSERT_EQ(scoopsim_test::RunScoopsim("run " + scene + " --set dig.passes=1 -o " + out + common +
                                           " --checkpoint-every 0.02 --stop-after 0.5",
                                       log),
            0)
      << ReadText(log);
  const fs::path restart = TempDir() / "passes.restart.h5";
  ASSERT_TRUE(fs::exists(restart));
  EXPECT_LT(sim::ReadCheckpoint(restart.string()).time,
            sim::SavedRun(reference).Scoop().time.front() + 1.0)
      << "the checkpoint is not in pass 1";
  // Resumed with two passes and stopped again, in pass 2, then resumed once more (two passes
  // now).
  ASSERT_EQ(scoopsim_test::RunScoopsim("run --resume " + out + " --set dig.passes=2" + common +
                                           " --checkpoint-every 0.02 --stop-after 1.5",
                                       log),
            0)
      << ReadText(log);
  ASSERT_TRUE(fs::exists(restart));
  // Given the same --set again, which the checkpoint's text already ends with: not added twice
  // (the scene text, a root attribute, stays the reference's).
  ASSERT_EQ(
      scoopsim_test::RunScoopsim("run --resume " + out + " --set dig.passes=2" + common, log), 0)
      << ReadText(log);
  ExpectSameDatasets(reference, out);
  EXPECT_EQ(StateHash(out), StateHash(reference));
  EXPECT_EQ(RootAttributes(out), RootAttributes(reference));
  EXPECT_EQ(sim::SavedRun(out).Scoop().pass.back(), 2);
}

// `bench step --checkpoint R` steps the dig on from R (a mid-dig state: the scoop in the bed, the
// sleepers asleep, kept where `run --stop-after` stopped) under the scene R holds. Oracle: the
// uninterrupted run. Stepped past the dig's end (World::Step does nothing then), the bench's
// state hash is the run's final one, on 1 and 2 threads. --set takes on the checkpoint (its lists made again from the changed scene: a wider
// neighbor.skin gives more near pairs). Given both SCENE and --checkpoint, or neither: one line,
// exit 2.
TEST(CheckpointTest, BenchStepGoesOnFromACheckpoint) {
  const std::string scene = WriteScene("dig");  // two passes of ~1.05 s each
  const std::string reference = (TempDir() / "bench_reference.h5").string();
  const std::string out = (TempDir() / "bench.h5").string();
  const std::string log = (TempDir() / "bench.log").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("run " + scene + " -o " + reference + " --threads 1 -q",
                                       log),
            0)
      << ReadText(log);
  // No periodic checkpoint (600 s of wall time): --stop-after keeps the state it stopped at,
  // 0.5 s into the dig (not the one at its start).
  ASSERT_EQ(scoopsim_test::RunScoopsim("run " + scene + " -o " + out +
                                           " --threads 1 -q --checkpoint-every 600 "
                                           "--stop-after 0.5",
                                       log),
            0)
      << ReadText(log);
  const std::string restart = (TempDir() / "bench.restart.h5").string();
  ASSERT_TRUE(fs::exists(restart));
  EXPECT_NEAR(sim::ReadCheckpoint(restart).time, sim::SavedRun(out).Scoop().time.front() + 0.5,
              0.01);
  const std::string hash = StateHash(reference);
  ASSERT_EQ(hash.size(), 16u);
  auto json_of = [&](const std::string& args) {
    const std::string json = (TempDir() / "bench.json").string();
    EXPECT_EQ(scoopsim_test::RunScoopsim("bench step --checkpoint " + restart + args + " > " + json,
                                         log),
              0)
        << ReadText(log);
    return ReadText(json);
  };
  auto field = [](const std::string& json, const std::string& key) {
    const size_t at = json.find("\"" + key + "\":");
    return at == std::string::npos ? std::string()
                                   : json.substr(at, json.find_first_of(",}", at) - at);
  };
  std::string near_pairs;
  for (int threads : {1, 2}) {
    const std::string json =
        json_of(" --warm 0 --steps 400000 --threads " + std::to_string(threads));
    EXPECT_EQ(field(json, "state_hash"), "\"state_hash\":\"" + hash + "\"") << json;
    near_pairs = field(json, "near_pairs");
  }
  // The near pairs at the last near-list build: the scene's skin, then a wider one.
  const std::string short_run = json_of(" --warm 0 --steps 200 --threads 1");
  const std::string wider = json_of(" --warm 0 --steps 200 --threads 1 --set neighbor.skin=8e-3");
  const auto count = [&](const std::string& json) {
    const std::string f = field(json, "near_pairs");
    return f.empty() ? -1L : std::stol(f.substr(f.find(':') + 1));
  };
  EXPECT_GT(count(short_run), 0) << short_run;
  EXPECT_GT(count(wider), count(short_run)) << wider;
  // SCENE and --checkpoint, or neither.
  EXPECT_EQ(scoopsim_test::RunScoopsim("bench step " + scene + " --checkpoint " + restart, log), 2);
  EXPECT_EQ(ReadText(log),
            "scoopsim: bench step: expected a SCENE or --checkpoint FILE (one of them)\n");
  EXPECT_EQ(scoopsim_test::RunScoopsim("bench step", log), 2);
  EXPECT_EQ(ReadText(log),
            "scoopsim: bench step: expected a SCENE or --checkpoint FILE (one of them)\n");
}

// A checkpoint is refused with one line, exit 2, when the scene given is not the one it was made
// from, or when its format version is another.
TEST(CheckpointTest, MismatchIsRefused) {
  const std::string scene = WriteScene("plain");
  const std::string out = (TempDir() / "mismatch.h5").string();
  const std::string restart = (TempDir() / "mismatch.restart.h5").string();
  const std::string log = (TempDir() / "mismatch.log").string();
  // A checkpoint kept by SIGINT (written when stopped), then the scene changed.
  const pid_t pid =
      Spawn("run " + scene + " -o " + out + " --threads 1 -q --checkpoint-every 100", log);
  for (int k = 0; k < 60000 && !fs::exists(out); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(pid, SIGINT);
  ASSERT_EQ(Wait(pid), 130) << ReadText(log);
  ASSERT_TRUE(fs::exists(restart)) << ReadText(log);
  std::ofstream(scene, std::ios::app) << "# changed\n";
  EXPECT_EQ(scoopsim_test::RunScoopsim("run " + scene + " --resume " + out + " -q", log), 2);
  std::string text = ReadText(log);
  EXPECT_EQ(text, "scoopsim: " + restart + ": made from another scene text than " + scene +
                      "'s (changed since?); resume with the scene it was made from (or with "
                      "more dig.passes, --set dig.passes=N)\n");
  // Another format version.
  const hid_t file = H5Fopen(restart.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const double other = 99;
  const hid_t attribute = H5Aopen(file, "format_version", H5P_DEFAULT);
  H5Awrite(attribute, H5T_NATIVE_DOUBLE, &other);
  H5Aclose(attribute);
  H5Fclose(file);
  EXPECT_EQ(scoopsim_test::RunScoopsim("run --resume " + out + " -q", log), 2);
  text = ReadText(log);
  EXPECT_EQ(text.find("scoopsim: " + restart + ": attribute format_version: expected 3, got 99"),
            0u)
      << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

}  // namespace

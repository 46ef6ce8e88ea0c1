// A seeded mutation fuzzer of the scene loader and the bed loader (issue 22: "every outcome is a
// clean exit with a known status, never a signal or a hang"), and of the URDF and sweep file
// readers (issue 42). Each scene case mutates a good dig scene or the bed file it names and runs
// `scoopsim check SCENE` (LoadScene, then Preflight, which reads the bed file: everything `run`
// does before its first step) under `timeout`. Every case must exit 0 (accepted) or 2 (refused,
// with exactly one line on stderr), with no sanitizer report; the test prints the table of
// outcomes. The seed is fixed, so a failure replays: the case's scene, bed and stderr are kept in
// the test's folder under its number.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../cli_util.h"
#include "bad_input_util.h"

namespace sim {
namespace {

namespace fs = std::filesystem;
using scoopsim_test::SetBedValue;
using scoopsim_test::WriteText;

constexpr uint64_t kSeed = 22;
constexpr int kSceneCases = 200;
constexpr int kBedCases = 100;

// Values that break parsers and ranges: non-finite, extreme, negative, empty, wrong type.
const char* const kBadTokens[] = {"nan",   "inf",    "-inf",   "-1",   "0",
                                  "1e300", "1e-300", "-1e300", "1e18", "",
                                  "[]",    "{}",     "x",      "2.5",  "9223372036854775808",
                                  "[1, 2", "~",      "true",   "0x10", "-0"};
const double kBadValues[] = {NAN, HUGE_VAL, -HUGE_VAL, 0.0, -1.0, 1e300, -1e300, 1e-300, 0.5, 5e-3};

class Fuzz {
 public:
  Fuzz() : dir_(scoopsim_test::ProcessTempDir("fuzz")), rng_(kSeed) {
    WriteText(dir_ / "lattice.yaml", scoopsim_test::DigSceneText(""));
    scoopsim_test::WriteLatticeBed((dir_ / "lattice.yaml").string(), Bed());
    scene_ = scoopsim_test::DigSceneText("");
  }

  std::string Bed() const { return (dir_ / "bed.h5").string(); }
  uint64_t Below(uint64_t n) { return rng_() % n; }

  // The good scene with 1 to 3 mutations of its text.
  std::string MutateScene() { return MutateText(scene_); }

  // `good` (a scene, a sweep file, a URDF) with 1 to 3 mutations of its text: a value replaced by
  // a bad token, a line deleted, doubled or swapped, a character replaced by YAML or XML syntax,
  // the text cut short.
  std::string MutateText(const std::string& good) {
    std::string text = good;
    for (uint64_t k = 0, n = 1 + Below(3); k < n; ++k) {
      std::vector<std::string> lines;
      std::istringstream in(text);
      for (std::string line; std::getline(in, line);) lines.push_back(line);
      if (lines.empty()) break;
      const size_t at = Below(lines.size());
      switch (Below(6)) {
        case 0: {  // a number (or the value after a colon or '="') replaced by a bad token
          std::string& line = lines[at];
          const size_t start = line.find_first_of("0123456789:\"");
          if (start == std::string::npos) break;
          size_t begin = line[start] == ':' ? start + 2 : (line[start] == '"' ? start + 1 : start);
          begin = std::min(begin, line.size());
          const size_t end = std::min(line.find_first_of(",]}\" ", begin), line.size());
          line.replace(begin, end - begin, kBadTokens[Below(std::size(kBadTokens))]);
          break;
        }
        case 1:  // a line deleted
          lines.erase(lines.begin() + static_cast<long>(at));
          break;
        case 2:  // a line doubled
          lines.insert(lines.begin() + static_cast<long>(at), lines[at]);
          break;
        case 3: {  // a character replaced by YAML syntax
          std::string& line = lines[at];
          const char syntax[] = ":[]{}-,#&*!|>'\"%@` \t<>/=";
          if (!line.empty()) line[Below(line.size())] = syntax[Below(sizeof syntax - 1)];
          break;
        }
        case 4:  // the text cut short
          lines.resize(at);
          break;
        default:  // two lines swapped
          std::swap(lines[at], lines[Below(lines.size())]);
      }
      text.clear();
      for (const std::string& line : lines) text += line + "\n";
    }
    return text;
  }

  // A copy of the good bed with one value, dataset or byte range spoiled, as `path`.
  void MutateBed(const std::string& path) {
    fs::copy_file(Bed(), path, fs::copy_options::overwrite_existing);
    const char* const doubles[] = {"/particles/position",         "/particles/velocity",
                                   "/particles/angular_velocity", "/particles/force",
                                   "/particles/torque",           "/particles/radius"};
    const char* const links[] = {"/particles/position", "/particles/radius", "/particles/id",
                                 "/materials/names",    "/contacts/a",       "/contacts/shear",
                                 "/particles/material", "/snapshots"};
    switch (Below(4)) {
      case 0:
      case 1: {  // a value
        const char* name = doubles[Below(std::size(doubles))];
        const bool vector = std::string(name) != "/particles/radius";
        SetBedValue(path, name, Below(1380), vector ? Below(3) : 0,
                    kBadValues[Below(std::size(kBadValues))]);
        break;
      }
      case 2: {  // a dataset, a group or an attribute removed
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        const uint64_t pick = Below(std::size(links) + 1);
        if (pick < std::size(links)) {
          H5Ldelete(file, links[pick], H5P_DEFAULT);
        } else {
          H5Adelete(file, "time");
        }
        H5Fclose(file);
        break;
      }
      default:  // the file cut short
        fs::resize_file(path, Below(fs::file_size(path)));
    }
  }

  // Runs `scoopsim check` on `scene_text` (next to its bed); returns the exit status, or 128 +
  // the signal, 124 for a hang. Sets *one_line to whether stderr holds one "scoopsim: " line and
  // *clean to whether it holds no sanitizer report.
  int Check(int index, const std::string& scene_text, bool* one_line, bool* clean) {
    return Run(index, scene_text, ".yaml", "check FILE", one_line, clean);
  }

  // Runs `scoopsim COMMAND`, FILE in `command` replaced by a file of `text` (named with
  // `extension`), as Check does.
  int Run(int index, const std::string& input, const std::string& extension,
          const std::string& command_line, bool* one_line, bool* clean) {
    const fs::path scene = dir_ / ("case_" + std::to_string(index) + extension);
    const fs::path err = dir_ / ("case_" + std::to_string(index) + ".err");
    WriteText(scene, input);
    std::string args = command_line;
    args.replace(args.find("FILE"), 4, "'" + scene.string() + "'");
    const std::string command = "timeout -s KILL 60 '" + std::string(SCOOPSIM_BINARY) + "' " +
                                args + " >/dev/null 2>'" + err.string() + "'";
    const int raw = std::system(command.c_str());
    int status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
    if (status == 137) status = 124;  // killed by timeout
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    const std::string s = text.str();
    *one_line = s.rfind("scoopsim: ", 0) == 0 && s.find('\n') == s.size() - 1;
    *clean =
        s.find("Sanitizer") == std::string::npos && s.find("runtime error") == std::string::npos;
    if (status == 0 || (status == 2 && *one_line && *clean)) {
      fs::remove(scene);
      fs::remove(err);
    }
    return status;
  }

  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  std::mt19937_64 rng_;  // raw draws only (no std distribution): the same cases everywhere
  std::string scene_;
};

// Case `k` exited 0, or 2 with one line; no sanitizer report either way.
void ExpectCleanOutcome(int k, int status, bool one_line, bool clean, const fs::path& dir) {
  EXPECT_TRUE(status == 0 || status == 2)
      << "case " << k << ": status " << status << " (124: hang, > 128: signal); see " << dir;
  if (status == 2) {
    EXPECT_TRUE(one_line) << "case " << k << ": not one line; see " << dir;
  }
  EXPECT_TRUE(clean) << "case " << k << ": a sanitizer report; see " << dir;
}

TEST(InputFuzzTest, EveryMutationExitsCleanlyWithAKnownStatus) {
  Fuzz fuzz;
  const auto t0 = std::chrono::steady_clock::now();
  std::map<std::string, std::map<int, int>> table;  // loader -> status -> cases
  for (int k = 0; k < kSceneCases + kBedCases; ++k) {
    const bool scene_case = k < kSceneCases;
    // A scene case mutates the scene of a bed still to be poured (no bed file: loading one
    // costs a dem::System's set-up, ~0.2 s); a bed case names a mutated copy of the bed.
    std::string text;
    if (scene_case) {
      text = fuzz.MutateScene();
    } else {
      const std::string bed = "bed_" + std::to_string(k) + ".h5";
      fuzz.MutateBed((fuzz.dir() / bed).string());
      text = scoopsim_test::DigSceneText(bed);
    }
    bool one_line = false, clean = false;
    const int status = fuzz.Check(k, text, &one_line, &clean);
    ++table[scene_case ? "scene" : "bed"][status];
    ExpectCleanOutcome(k, status, one_line, clean, fuzz.dir());
    if (!scene_case && status != 2 && status != 0) continue;
    if (!scene_case) fs::remove(fuzz.dir() / ("bed_" + std::to_string(k) + ".h5"));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("input fuzz (seed %llu): %d scene + %d bed mutations in %.1f s\n",
              static_cast<unsigned long long>(kSeed), kSceneCases, kBedCases, seconds);
  for (const auto& [loader, counts] : table)
    for (const auto& [status, n] : counts)
      std::printf("  %-5s exit %3d: %d\n", loader.c_str(), status, n);
  // Both outcomes occur: the fuzzer reaches past the first check.
  EXPECT_GT(table["scene"][0], 0);
  EXPECT_GT(table["scene"][2], 0);
  EXPECT_GT(table["bed"][2], 0);
}

// The same for the other inputs a user writes (issue 42): URDFs (the lander's arm, mutated, read
// by `scoopsim arm info`) and sweep files (scenes/sweeps/tiny.yaml, mutated, its cases made and
// checked by `scoopsim sweep --list`, which runs none). Every case exits 0 or 2 with one line.
TEST(InputFuzzTest, EveryUrdfAndSweepMutationExitsCleanlyWithAKnownStatus) {
  Fuzz fuzz;
  const std::string source = SCOOPSIM_SOURCE_DIR;
  const std::string urdf = scoopsim_test::ReadText(source + "/assets/lander_arm.urdf");
  // The URDF names its mesh relative to its folder: a copy of the scoop beside the cases.
  fs::copy_file(source + "/assets/scoop.stl", fuzz.dir() / "scoop.stl");
  std::string sweep = scoopsim_test::ReadText(source + "/scenes/sweeps/tiny.yaml");
  sweep.replace(sweep.find("scene: tiny_scene.yaml"), 22,
                "scene: " + source + "/scenes/sweeps/tiny_scene.yaml");
  constexpr int kUrdfCases = 100, kSweepCases = 40;
  std::map<std::string, std::map<int, int>> table;  // input -> status -> cases
  for (int k = 0; k < kUrdfCases + kSweepCases; ++k) {
    const bool urdf_case = k < kUrdfCases;
    bool one_line = false, clean = false;
    const std::string list = "sweep FILE --list -o '" + (fuzz.dir() / "sweep_out").string() + "'";
    const int status =
        urdf_case ? fuzz.Run(k, fuzz.MutateText(urdf), ".urdf", "arm info FILE", &one_line, &clean)
                  : fuzz.Run(k, fuzz.MutateText(sweep), ".yaml", list, &one_line, &clean);
    ++table[urdf_case ? "urdf" : "sweep"][status];
    ExpectCleanOutcome(k, status, one_line, clean, fuzz.dir());
  }
  std::printf("input fuzz (seed %llu): %d URDF + %d sweep mutations\n",
              static_cast<unsigned long long>(kSeed), kUrdfCases, kSweepCases);
  for (const auto& [input, counts] : table)
    for (const auto& [status, n] : counts)
      std::printf("  %-5s exit %3d: %d\n", input.c_str(), status, n);
  EXPECT_GT(table["urdf"][0], 0);
  EXPECT_GT(table["urdf"][2], 0);
  EXPECT_GT(table["sweep"][0], 0);
  EXPECT_GT(table["sweep"][2], 0);
}

}  // namespace
}  // namespace sim

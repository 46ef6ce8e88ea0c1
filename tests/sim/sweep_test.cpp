// Sweeps (sim/studies/sweep.cpp): the sweep file (cases from a grid and a list, errors at load with
// the line and key), status records, and end to end on scenes/sweeps/tiny.yaml (four cases, two
// passes each; its moves made faster, FastTiny): a plain run, a two-rank `mpirun` run, `--case I`
// and runs SIGKILLed mid-case (in a pass without checkpoints, in a pass with them, in the pour)
// then resumed all give the same table and case rows, bit for bit.
#include "sim/studies/sweep.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "sim/files/bed_io.h"
#include "sim/files/checkpoint.h"
#include "sim/files/saved_run.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;
const std::string kTiny = kSourceDir + "/scenes/sweeps/tiny.yaml";

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("sweep");
  return dir;
}

std::string ReadText(const fs::path& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

// A sweep file in the temporary folder over scenes/sweeps/tiny_scene.yaml.
// Takes the exclusive flock that a process running a case holds on its lock file `path` (made if
// missing): the descriptor, or -1 when the lock cannot be had. Closing it releases the lock.
int HoldLock(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
  if (fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

std::string WriteSweep(const std::string& name, const std::string& body) {
  const fs::path path = TempDir() / name;
  std::ofstream(path) << "scene: " << kSourceDir << "/scenes/sweeps/tiny_scene.yaml\n" << body;
  return path.string();
}

// The InputError LoadSweep throws for `body`.
sim::InputError LoadError(const std::string& body) {
  try {
    sim::LoadSweep(WriteSweep("bad.yaml", body));
  } catch (const sim::InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << body;
  return sim::InputError("none");
}

TEST(SweepFileTest, GridThenListInOrder) {
  const sim::Sweep sweep = sim::LoadSweep(WriteSweep("ok.yaml", R"(grid:
  bed.material: [snow, ice]
  dig.bite_depth: {b5: 0.005, b10: 0.01}
cases:
  - {name: deep, set: {dig.bite_depth: 0.012, dig.passes: 1}}
  - set: {dig.trajectory.linear.distance: 0.03}
)"));
  ASSERT_EQ(sweep.cases.size(), 6u);
  const char* names[] = {"snow_b5", "snow_b10", "ice_b5", "ice_b10", "deep", "0.03"};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(sweep.cases[i].name, names[i]);
    EXPECT_EQ(sweep.cases[i].index, i);
    EXPECT_GT(sweep.cases[i].estimate, 0);
  }
  EXPECT_EQ(sweep.cases[2].scene.bed.material, "ice");
  EXPECT_EQ(sweep.cases[2].scene.dig.bite_depth, 0.005);
  EXPECT_EQ(sweep.cases[4].scene.dig.passes, 1);
  EXPECT_EQ(sweep.cases[4].scene.dig.bite_depth, 0.012);
  EXPECT_EQ(sweep.cases[5].scene.dig.trajectory.moves[2].amount, 0.03);
  // The case's scene text is the edited base scene, loadable as it stands.
  const sim::Scene again =
      sim::LoadSceneText(sweep.cases[3].scene.path, sweep.cases[3].scene.yaml_text);
  EXPECT_EQ(again.bed.material, "ice");
  EXPECT_EQ(again.dig.bite_depth, 0.01);
  // ... made as the command line's --set makes a scene: the base file's text, whole, then the
  // case's settings as `# scoopsim --set KEY=VALUE` lines ("[i]" as ".i").
  const std::string base = ReadText(kSourceDir + std::string("/scenes/sweeps/tiny_scene.yaml"));
  EXPECT_EQ(sweep.cases[3].scene.yaml_text.compare(0, base.size(), base), 0);
  EXPECT_EQ(sim::LoadScene(sweep.cases[3].scene.path, {"bed.material=ice", "dig.bite_depth=0.01"})
                .dig.bite_depth,
            0.01);
  const std::string text = sweep.cases[3].scene.yaml_text;
  EXPECT_NE(
      text.find("\n# scoopsim --set bed.material=ice\n# scoopsim --set dig.bite_depth=0.01\n"),
      std::string::npos)
      << text;
}

// Two sweep files that make the same case make the same scene text, so either finds the other's
// case done (scenes/sweeps/lookup_snow.yaml runs lookup.yaml's snow cases while the ice bed is
// poured). Until 2026-12-06 the text named the sweep file, and lookup.yaml saw the snow cases as
// "made from another scene text".
TEST(SweepFileTest, TheSameCaseFromAnotherSweepFileHasTheSameText) {
  const sim::Sweep all = sim::LoadSweep(WriteSweep("all.yaml", R"(grid:
  bed.material: [snow, ice]
  dig.bite_depth: {b5: 0.005, b10: 0.01}
)"));
  const sim::Sweep snow = sim::LoadSweep(WriteSweep("snow_only.yaml", R"(grid:
  bed.material: [snow]
  dig.bite_depth: {b5: 0.005, b10: 0.01}
)"));
  ASSERT_EQ(all.cases.size(), 4u);
  ASSERT_EQ(snow.cases.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(snow.cases[i].name, all.cases[i].name);
    EXPECT_EQ(snow.cases[i].scene.yaml_text, all.cases[i].scene.yaml_text);
  }
  EXPECT_NE(all.cases[0].scene.yaml_text, all.cases[1].scene.yaml_text);
}

TEST(SweepFileTest, ListIndexAndRemovalAreOverrides) {
  // tiny_scene.yaml: dig.trajectory.start [0.13, 0.08], dig.interval 2.0e-3.
  const sim::Sweep sweep = sim::LoadSweep(WriteSweep("index.yaml", R"(cases:
  - name: far
    set:
      dig.trajectory.start[1]: 0.09
      dig.interval: ~
)"));
  ASSERT_EQ(sweep.cases.size(), 1u);
  const sim::Scene& scene = sweep.cases[0].scene;
  const sim::Scene base = sim::LoadScene(scene.path);
  EXPECT_EQ(base.dig.interval, 2.0e-3);
  EXPECT_EQ(scene.dig.interval, sim::DigSpec{}.interval);  // the key removed: its default
  EXPECT_NE(scene.yaml_text.find("\n# scoopsim --set dig.trajectory.start.1=0.09\n"),
            std::string::npos)
      << scene.yaml_text;
  EXPECT_EQ(base.dig.trajectory.pivot_start.y, 0.08);
  EXPECT_EQ(scene.dig.trajectory.pivot_start.y, 0.09);  // dig.trajectory.start: [x, y]
}

TEST(SweepFileTest, UnknownSceneKeyPathFailsAtItsLine) {
  const sim::InputError e = LoadError("grid:\n  bed.material: [snow]\n  bed.radiuss: [0.01]\n");
  EXPECT_EQ(e.line(), 4) << e.what();  // line 1 is the scene key WriteSweep adds
  EXPECT_EQ(e.key(), "bed.radiuss");
  EXPECT_NE(e.expected().find("one of the keys"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("bad.yaml:4: bed.radiuss"), std::string::npos) << e.what();
  // A path through a value that is not a map, and a malformed path.
  const sim::InputError through = LoadError("grid:\n  bed.material.x: [snow]\n");
  EXPECT_EQ(through.line(), 3) << through.what();
  const sim::InputError malformed = LoadError("grid:\n  bed..material: [snow]\n");
  EXPECT_EQ(malformed.line(), 3) << malformed.what();
  // A bad value is reported at the value.
  const sim::InputError value = LoadError("grid:\n  dig.bite_depth:\n    - 0.01\n    - -2\n");
  EXPECT_EQ(value.line(), 5) << value.what();
  EXPECT_EQ(value.key(), "dig.bite_depth");
}

// A sweep digs kinematically: a case that gives the scene an arm is refused at its setting's
// line, key `arm` (a base scene with one, at its own line: hand_cases_test.cpp).
TEST(SweepFileTest, CaseWithAnArmIsRefused) {
  const sim::InputError e = LoadError(
      "cases:\n  - name: witharm\n    set: {arm: {urdf: ../../assets/lander_arm.urdf}}\n");
  EXPECT_EQ(e.line(), 4) << e.what();
  EXPECT_EQ(e.key(), "arm") << e.what();
  EXPECT_NE(e.expected().find("a sweep digs kinematically"), std::string::npos) << e.what();
}

TEST(SweepFileTest, EmptyGridFails) {
  for (const char* body :
       {"grid: {}\n", "grid:\n  bed.material: []\n", "grid:\n  dig.bite_depth: {}\n",
        "notes: nothing to run\n", "cases: []\n"}) {
    const sim::InputError e = LoadError(body);
    EXPECT_GT(e.line(), 0) << e.what();
    EXPECT_NE(e.expected().find("non-empty"), std::string::npos) << body << ": " << e.what();
  }
}

TEST(SweepFileTest, DuplicateCaseNamesFail) {
  const sim::InputError e = LoadError(
      "grid:\n  bed.material: [snow, ice]\ncases:\n  - {name: ice, set: {dig.passes: 1}}\n");
  EXPECT_EQ(e.line(), 5) << e.what();
  EXPECT_NE(std::string(e.what()).find("unique case names"), std::string::npos) << e.what();
  EXPECT_NE(e.note().find("first at line 3"), std::string::npos) << e.what();
  const sim::InputError labels = LoadError("grid:\n  dig.bite_depth: {a: 0.01, a: 0.02}\n");
  EXPECT_GT(labels.line(), 0) << labels.what();
}

// Defect: a key given twice in a sweep file was taken silently (the second grid dropped, a case
// named "0.01_0.02"); the scene loader refused them, the sweep loader did not. Now each is
// refused at its second line.
TEST(SweepFileTest, DuplicateKeysFail) {
  const std::string scene = "scene: " + kSourceDir + "/scenes/sweeps/tiny_scene.yaml\n";
  const auto error = [](const std::string& text) {
    const fs::path path = TempDir() / "dup.yaml";
    std::ofstream(path) << text;
    try {
      sim::LoadSweep(path.string());
    } catch (const sim::InputError& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return std::string();
  };
  EXPECT_NE(error(scene + scene + "grid: {dig.passes: [1]}\n")
                .find("dup.yaml:2: scene: expected each key once, got a second 'scene' (first "
                      "at line 1)"),
            std::string::npos);
  EXPECT_NE(error(scene + "grid: {dig.passes: [1]}\ngrid: {dig.bite_depth: [0.01]}\n")
                .find("dup.yaml:3: grid: expected each key once"),
            std::string::npos);
  EXPECT_NE(error(scene + "grid: {dig.bite_depth: [0.01], dig.bite_depth: [0.02]}\n")
                .find("dup.yaml:2: grid.dig.bite_depth: expected each key once"),
            std::string::npos);
  EXPECT_NE(error(scene + "cases:\n  - {name: a, set: {dig.passes: 1, dig.passes: 2}}\n")
                .find("dup.yaml:3: cases[0].set.dig.passes: expected each key once"),
            std::string::npos);
}

// Defect: outputs that named a file of the wrong kind were written over or failed with a
// filesystem error (exit 1): `table export-csv T -o T` turned the table into CSV, `table build
// DIR -o DIR/cases/x.h5` wrote over a case file, `-o` a folder, a grid of 1e15 points, `sweep -o`
// a file. Each is now one line, exit 2, before any work, the inputs untouched.
TEST(SweepFileTest, OutputsOfTheWrongKindAreRefused) {
  const fs::path dir = TempDir() / "wrong_kind";
  fs::create_directories(dir / "cases");
  const fs::path table = dir / "t.h5";
  std::ofstream(table) << "not a table";
  const fs::path case_file = dir / "cases" / "a.h5";
  std::ofstream(case_file) << "not a case";
  const std::string log = (TempDir() / "wrong_kind.log").string();
  const auto refused = [&](const std::string& args, const std::string& start) {
    SCOPED_TRACE(args);
    EXPECT_EQ(scoopsim_test::RunScoopsim(args, log), 2);
    const std::string text = ReadText(log);
    EXPECT_EQ(text.rfind("scoopsim: " + start, 0), 0u) << text;
    EXPECT_EQ(text.find('\n'), text.size() - 1) << text;
  };
  refused("table export-csv " + table.string() + " -o " + table.string(),
          table.string() + ": -o names the run's own input (TABLE = ");
  refused("table export-csv " + table.string() + " -o " + dir.string(),
          "-o " + dir.string() + ": expected a file to write, got a folder");
  refused("table build " + dir.string() + " -o " + case_file.string(),
          "-o " + case_file.string() + ": names a file in " + dir.string() + "/cases/");
  refused("table build " + dir.string() + " -o " + (dir / "t2.h5").string() +
              " --rho-max-mm 1e12 --rho-step-mm 1e-3",
          "--rho-max-mm 1e+12 / --rho-step-mm 0.001: expected at most 1e7 grid points");
  refused("sweep " + kTiny + " -o " + table.string(),
          "-o " + table.string() + ": expected the sweep's output folder, got a file");
  refused("sweep " + dir.string(), dir.string() + ": expected a sweep file (YAML), got a folder");
  refused("sweep " + kTiny + " --checkpoint-every nan -o " + dir.string(),
          "--checkpoint-every: expected a finite number >= 0 (s), got nan");
  EXPECT_EQ(ReadText(table), "not a table");
  EXPECT_EQ(ReadText(case_file), "not a case");
}

// Bad sweep files exit 2 with one line naming the file and line.
TEST(SweepFileTest, CommandLineExitsTwo) {
  const std::string sweep = WriteSweep("cli_bad.yaml", "grid:\n  bed.nope: [1]\n");
  const std::string log = (TempDir() / "cli_bad.log").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("sweep " + sweep + " -o " + (TempDir() / "x").string(), log),
            2);
  EXPECT_NE(ReadText(log).find("cli_bad.yaml:3: bed.nope"), std::string::npos) << ReadText(log);
  EXPECT_EQ(
      scoopsim_test::RunScoopsim("sweep " + kTiny + " --case 4 -o " + (TempDir() / "x").string()),
      2);
}

// `--list`'s last column (sim::CaseState) from records written here, one per state; no DEM. A
// running case whose lock another open file holds is running; one whose lock nobody holds was
// killed (flock dies with its holder).
TEST(SweepFileTest, ListSaysWhereEachCaseStands) {
  const sim::Sweep sweep = sim::LoadSweep(kTiny);
  ASSERT_EQ(sweep.cases.size(), 4u);
  const fs::path dir = TempDir() / "list";
  fs::create_directories(dir / "cases");
  const auto record = [&](int k, const std::string& state, const std::string& message) {
    sim::CaseStatus s;
    s.state = state;
    s.index = k;
    s.passes = 2;
    s.passes_done = state == "stopped" ? 1 : 0;
    s.scene_hash = sim::TextHash(sweep.cases[k].scene.yaml_text);
    s.exit_status = state == "failed" ? 3 : 0;
    s.bed_cpu_s = 12.25;
    s.pass_cpu_s = 5;
    s.message = message;
    sim::WriteCaseStatus((dir / "cases" / (sweep.cases[k].name + ".status")).string(), s);
  };
  const auto state = [&](int k) { return sim::CaseState(sweep.cases[k], dir.string()); };
  EXPECT_EQ(state(0), "not started");
  record(0, "done", "");
  EXPECT_EQ(state(0), "done, but its file is missing");
  std::ofstream(dir / "cases" / (sweep.cases[0].name + ".h5")) << "x";
  EXPECT_EQ(state(0), "done");
  record(1, "stopped", "pass 2 did not finish");
  EXPECT_EQ(
      state(1),
      "stopped: pass 2 of 2, 5.0 CPU s in it to its last keep (kept: the same command goes on)");
  record(2, "running", "making the bed");
  EXPECT_EQ(state(2),
            "killed: the pour, 12.2 CPU s to its last keep (the same command goes on from its last "
            "keep)");
  {
    const std::string lock = (dir / "cases" / (sweep.cases[2].name + ".lock")).string();
    const int fd = HoldLock(lock);
    ASSERT_GE(fd, 0);
    EXPECT_EQ(state(2),
              "running (another process holds its lock): the pour, 12.2 CPU s to its last keep");
    ::close(fd);
  }
  record(3, "failed", "the box holds only 10 of bed.count = 20 particles");
  EXPECT_EQ(state(3), "failed (exit 3): the box holds only 10 of bed.count = 20 particles");
  // Another scene text: the case's own record, not this one's.
  record(3, "done", "");
  sim::CaseStatus other =
      sim::ReadCaseStatus((dir / "cases" / (sweep.cases[3].name + ".status")).string());
  other.scene_hash = "0123456789abcdef";
  sim::WriteCaseStatus((dir / "cases" / (sweep.cases[3].name + ".status")).string(), other);
  EXPECT_EQ(state(3), "made from another scene text");
  // The list: the state is the fifth column with a folder, absent without one.
  const std::string with = sim::SweepCaseList(sweep, dir.string());
  EXPECT_NE(with.find("\t1.79e+08\tdone\n"), std::string::npos) << with;
  const std::string without = sim::SweepCaseList(sweep);
  EXPECT_EQ(without.find("done"), std::string::npos) << without;
}

TEST(SweepFileTest, StatusRecordRoundTrips) {
  sim::CaseStatus s;
  s.state = "running";
  s.index = 3;
  s.passes = 5;
  s.passes_done = 2;
  s.surface = 0.1 + 1e-17 * 3;  // any double
  s.clear_z = 1.0 / 3.0;
  s.scene_hash = sim::TextHash("scene");
  s.message = "pass 3";
  s.bed_cpu_s = 12.25;
  const std::string path = (TempDir() / "x.status").string();
  sim::WriteCaseStatus(path, s);
  const sim::CaseStatus r = sim::ReadCaseStatus(path);
  EXPECT_EQ(r.state, s.state);
  EXPECT_EQ(r.index, 3);
  EXPECT_EQ(r.passes_done, 2);
  EXPECT_EQ(r.surface, s.surface);
  EXPECT_EQ(r.clear_z, s.clear_z);
  EXPECT_EQ(r.scene_hash, s.scene_hash);
  EXPECT_EQ(r.message, "pass 3");
  EXPECT_EQ(r.bed_cpu_s, 12.25);
  EXPECT_EQ(sim::ReadCaseStatus((TempDir() / "none.status").string()).state, "");
}

// ---- End to end

// Every dataset of an HDF5 file as bytes (numbers in their native type, strings as text), by
// name; datasets under `skip` left out.
herr_t Visit(hid_t object, const char* name, const H5O_info_t* info, void* data) {
  if (info->type != H5O_TYPE_DATASET) return 0;
  auto& out = *static_cast<std::map<std::string, std::string>*>(data);
  const hid_t d = H5Dopen2(object, name, H5P_DEFAULT);
  const hid_t type = H5Dget_type(d);
  const hid_t space = H5Dget_space(d);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::string bytes;
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0) {
    const hid_t memory = H5Tcopy(type);
    std::vector<char*> strings(static_cast<size_t>(n));
    H5Dread(d, memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.data());
    for (char* s : strings) bytes += std::string(s ? s : "") + '\0';
    H5Dvlen_reclaim(memory, space, H5P_DEFAULT, strings.data());
    H5Tclose(memory);
  } else {
    const hid_t native = H5Tget_native_type(type, H5T_DIR_ASCEND);
    bytes.resize(static_cast<size_t>(n) * H5Tget_size(native));
    H5Dread(d, native, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
    H5Tclose(native);
  }
  out[name] = bytes;
  H5Sclose(space);
  H5Tclose(type);
  H5Dclose(d);
  return 0;
}

std::map<std::string, std::string> Datasets(const fs::path& path, const std::string& skip = "") {
  std::map<std::string, std::string> out;
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << path;
  if (f < 0) return out;
  H5Ovisit2(f, H5_INDEX_NAME, H5_ITER_INC, Visit, &out, H5O_INFO_BASIC);
  H5Fclose(f);
  if (!skip.empty()) {
    for (auto it = out.begin(); it != out.end();)
      it = it->first.rfind(skip, 0) == 0 ? out.erase(it) : std::next(it);
  }
  return out;
}

// Same datasets, same bytes; failures name the dataset.
void ExpectSameData(const fs::path& a, const fs::path& b, const std::string& skip = "") {
  const auto x = Datasets(a, skip);
  const auto y = Datasets(b, skip);
  EXPECT_GT(x.size(), 5u) << a;
  ASSERT_EQ(x.size(), y.size()) << a << " vs " << b;
  for (const auto& [name, bytes] : x) {
    ASSERT_TRUE(y.count(name)) << name << " missing in " << b;
    EXPECT_TRUE(y.at(name) == bytes) << name << " differs: " << a << " vs " << b;
  }
}

std::string RootString(const fs::path& path, const std::string& name) {
  return sim::SavedRun(path.string()).RootAttribute(name);
}

const char* const kCases[] = {"snow_b5", "snow_b10", "ice_b5", "ice_b10"};

// One test, so that the plain sweep (the reference) runs once: ctest runs every test of this
// file in a process of its own. Cases run on one thread (the DEM gives the same bits on any
// count); the MPI ranks get one each.
// Copies case `name`'s file and status record from `from`/cases into `to`/cases, as a sweep that
// finished it there would have left them.
void CopyCase(const fs::path& from, const fs::path& to, const std::string& name) {
  for (const char* ext : {".h5", ".status"})
    fs::copy_file(from / "cases" / (name + ext), to / "cases" / (name + ext));
}

// The sweep of the end-to-end test below: scenes/sweeps/tiny.yaml's grid (the same four cases)
// on tiny_scene.yaml with both rotations at 180 deg/s instead of Table 1's 90 (the linear push
// and the second rotation start earlier to match): the same bed and the same moves in the same
// order, each pass 1.5 s of simulated time instead of 2.4 s, which is what the test costs. (At
// 270 deg/s the deep ice case throws a particle out of the box; 180 keeps every case valid.)
// Written once into the test's folder, its relative paths made absolute.
const std::string& FastTiny() {
  static const std::string path = [] {
    std::string scene = scoopsim_test::ReadText(kSourceDir + "/scenes/sweeps/tiny_scene.yaml");
    const std::pair<std::string, std::string> edits[] = {
        {"materials: ../", "materials: " + kSourceDir + "/scenes/"},
        {"mesh: ../../", "mesh: " + kSourceDir + "/"},
        {"rotation1: {start: 0.2}", "rotation1: {start: 0.2, rate: 180}"},
        {"linear: {start: 1.2,", "linear: {start: 0.75,"},
        {"rotation2: {start: 1.35}", "rotation2: {start: 0.9, rate: 180}"}};
    for (const auto& [from, to] : edits) {
      const size_t at = scene.find(from);
      EXPECT_NE(at, std::string::npos) << "tiny_scene.yaml has no '" << from << "'";
      if (at != std::string::npos) scene.replace(at, from.size(), to);
    }
    std::ofstream(TempDir() / "fast_tiny_scene.yaml") << scene;
    std::string sweep = scoopsim_test::ReadText(kTiny);
    const std::string base = "scene: tiny_scene.yaml";
    EXPECT_NE(sweep.find(base), std::string::npos) << kTiny;
    if (sweep.find(base) != std::string::npos)
      sweep.replace(sweep.find(base), base.size(), "scene: fast_tiny_scene.yaml");
    std::ofstream(TempDir() / "fast_tiny.yaml") << sweep;
    return (TempDir() / "fast_tiny.yaml").string();
  }();
  return path;
}

// The tiny sweep on 2 MPI ranks into `dir`, its output in `log`: the raw std::system status.
int MpiSweep(const fs::path& dir, const std::string& log) {
  const std::string cmd =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "OMPI_MCA_rmaps_base_oversubscribe=1 " +
      std::string(SCOOPSIM_MPIEXEC) + " -np 2 --oversubscribe " + SCOOPSIM_BINARY + " sweep " +
      FastTiny() + " -o " + dir.string() + " -q >" + log + " 2>&1";
  return std::system(cmd.c_str());
}

TEST(SweepRunTest, PlainMpiOneCaseAndResumedSweepsAgree) {
  const fs::path plain = TempDir() / "plain";
  const std::string log = (TempDir() / "plain.log").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim(
                "sweep " + FastTiny() + " -o " + plain.string() + " --threads 1 -q", log),
            0)
      << ReadText(log);
  for (const char* name : kCases) {
    EXPECT_TRUE(fs::exists(plain / "cases" / (std::string(name) + ".h5"))) << name;
    EXPECT_EQ(
        sim::ReadCaseStatus((plain / "cases" / (std::string(name) + ".status")).string()).state,
        "done");
    EXPECT_FALSE(fs::exists(plain / "cases" / (std::string(name) + ".parts"))) << name;
  }
  ASSERT_TRUE(fs::exists(plain / "table.h5"));
  // One line per case start and end, with the wall time and the ETA.
  const std::string text = ReadText(log);
  EXPECT_NE(text.find("[3/4] ice_b10 started"), std::string::npos) << text;
  EXPECT_NE(text.find("of 4 finished, ETA"), std::string::npos) << text;
  // A case's file is a run's output with two passes, its scene the base scene with the case's
  // settings as --set lines, which whatever reads the text again applies.
  const sim::SavedRun run((plain / "cases" / "ice_b5.h5").string());
  const std::string scene = run.SceneYaml();
  EXPECT_NE(scene.find("\n# scoopsim --set bed.material=ice\n"), std::string::npos) << scene;
  EXPECT_NE(scene.find("\n# scoopsim --set dig.bite_depth=0.005\n"), std::string::npos) << scene;
  const sim::StoredDig stored = sim::ParseStoredDig(scene, "ice_b5.h5");
  EXPECT_EQ(stored.material, "ice");
  EXPECT_EQ(stored.bite_depth, 0.005);
  const sim::ScoopSeries scoop = run.Scoop();
  ASSERT_FALSE(scoop.empty());
  EXPECT_EQ(scoop.pass.front(), 1);
  EXPECT_EQ(scoop.pass.back(), 2);

  // A second plain run skips every case.
  const std::string again_log = (TempDir() / "again.log").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("sweep " + FastTiny() + " -o " + plain.string() + " -q",
                                       again_log),
            0);
  EXPECT_NE(ReadText(again_log).find("[0/4] snow_b5 skipped (done)"), std::string::npos);
  EXPECT_EQ(ReadText(again_log).find("started"), std::string::npos) << ReadText(again_log);

  {
    SCOPED_TRACE("mpirun -np 2");
    const fs::path mpi = TempDir() / "mpi";
    const std::string mpi_log = (TempDir() / "mpi.log").string();
    ASSERT_EQ(MpiSweep(mpi, mpi_log), 0) << ReadText(mpi_log);
    const std::string mpi_text = ReadText(mpi_log);
    EXPECT_NE(mpi_text.find("on 2 MPI ranks"), std::string::npos) << mpi_text;
    EXPECT_NE(mpi_text.find("(rank 1)"), std::string::npos) << mpi_text;
    ExpectSameData(plain / "table.h5", mpi / "table.h5");
    for (const char* name : kCases) {
      const fs::path file = fs::path("cases") / (std::string(name) + ".h5");
      ExpectSameData(plain / file, mpi / file, "sweep");  // /sweep/: wall and CPU times
      EXPECT_EQ(RootString(plain / file, "state_hash"), RootString(mpi / file, "state_hash"));
    }
  }
  {
    SCOPED_TRACE("--case 2");
    const fs::path one = TempDir() / "one";
    ASSERT_EQ(scoopsim_test::RunScoopsim("sweep " + FastTiny() + " --case 2 -o " + one.string() +
                                         " --threads 1 -q"),
              0);
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(one / "cases"))
      files.push_back(entry.path().filename().string());
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"ice_b5.h5", "ice_b5.lock", "ice_b5.status"}));
    EXPECT_FALSE(fs::exists(one / "table.h5"));
    ExpectSameData(plain / "cases" / "ice_b5.h5", one / "cases" / "ice_b5.h5", "sweep");
  }
  {
    SCOPED_TRACE("a case another process holds");
    // Three cases done (copied); this test holds snow_b10's lock, as a second sweep on the same
    // folder running it would. A plain sweep leaves that case to it: exit 0, no FAILED, and no
    // table, since not every case is done. --case on the held case fails (exit 1). When the
    // holder has finished (its files copied, its lock released), a sweep builds the table.
    const fs::path shared = TempDir() / "shared";
    fs::create_directories(shared / "cases");
    for (const char* name : {"snow_b5", "ice_b5", "ice_b10"}) CopyCase(plain, shared, name);
    const std::string lock = (shared / "cases" / "snow_b10.lock").string();
    const int fd = HoldLock(lock);
    ASSERT_GE(fd, 0);
    const std::string held_log = (TempDir() / "held.log").string();
    EXPECT_EQ(scoopsim_test::RunScoopsim("sweep " + FastTiny() + " -o " + shared.string() + " -q",
                                         held_log),
              0)
        << ReadText(held_log);
    const std::string text = ReadText(held_log);
    EXPECT_NE(text.find("[1/4] snow_b10 left to another process (it holds cases/snow_b10.lock)"),
              std::string::npos)
        << text;
    EXPECT_EQ(text.find("FAILED"), std::string::npos) << text;
    EXPECT_EQ(text.find("snow_b10 done"), std::string::npos) << text;
    EXPECT_FALSE(fs::exists(shared / "cases" / "snow_b10.status"));  // untouched: not its case
    EXPECT_FALSE(fs::exists(shared / "table.h5"));
    const std::string one_log = (TempDir() / "held_one.log").string();
    EXPECT_EQ(scoopsim_test::RunScoopsim(
                  "sweep " + FastTiny() + " --case 1 -o " + shared.string() + " -q", one_log),
              1);
    EXPECT_NE(ReadText(one_log).find("case snow_b10 is being run by another process"),
              std::string::npos)
        << ReadText(one_log);
    {
      SCOPED_TRACE("mpirun -np 2, the case held");
      const std::string mpi_log = (TempDir() / "held_mpi.log").string();
      // Not its log's last line: mpirun's forwarding at times drops a rank's last line at exit.
      EXPECT_EQ(MpiSweep(shared, mpi_log), 0) << ReadText(mpi_log);
      EXPECT_EQ(ReadText(mpi_log).find("FAILED"), std::string::npos) << ReadText(mpi_log);
      EXPECT_FALSE(fs::exists(shared / "cases" / "snow_b10.status"));
      EXPECT_FALSE(fs::exists(shared / "table.h5"));
    }
    CopyCase(plain, shared, "snow_b10");
    ::close(fd);
    EXPECT_EQ(scoopsim_test::RunScoopsim("sweep " + FastTiny() + " -o " + shared.string() + " -q"),
              0);
    ExpectSameData(plain / "table.h5", shared / "table.h5");
  }
  // Three cases done already (copied), then the sweep is SIGKILLed `kill` into ice_b10 (ice's
  // time step is longer than snow's: its case takes the fewest steps) with checkpoints every
  // `every` seconds of wall time, then resumed: the same table and rows. Returns the resumed
  // run's log.
  const auto kill_and_resume = [&](const std::string& folder, const std::string& kill,
                                   const std::string& every, const auto& while_killed) {
    const fs::path resumed = TempDir() / folder;
    fs::create_directories(resumed / "cases");
    for (const char* name : {"snow_b5", "snow_b10", "ice_b5"}) CopyCase(plain, resumed, name);
    const std::string killed_log = (TempDir() / (folder + ".killed.log")).string();
    const std::string cmd = "SCOOPSIM_SWEEP_KILL=ice_b10:" + kill + " " +
                            std::string(SCOOPSIM_BINARY) + " sweep " + FastTiny() + " -o " +
                            resumed.string() + " --threads 1 -q --checkpoint-every " + every +
                            " 2>" + killed_log;
    const int killed = std::system(cmd.c_str());
    if (kill.find(":TERM") != std::string::npos) {
      // The controlled stop: exit 130, the case kept and reported as stopped, not failed.
      const std::string text = ReadText(killed_log);
      EXPECT_TRUE(WIFEXITED(killed) && WEXITSTATUS(killed) == 130) << killed << ": " << text;
      EXPECT_NE(text.find("ice_b10 stopped after"), std::string::npos) << text;
      EXPECT_NE(text.find("kept; the same command goes on"), std::string::npos) << text;
      EXPECT_EQ(text.find("FAILED"), std::string::npos) << text;
    } else {
      EXPECT_TRUE(WIFSIGNALED(killed) ||
                  (WIFEXITED(killed) && WEXITSTATUS(killed) == 128 + SIGKILL))
          << killed << ": " << ReadText(killed_log);
    }
    EXPECT_FALSE(fs::exists(resumed / "table.h5"));
    while_killed(resumed / "cases" / "ice_b10.parts",
                 sim::ReadCaseStatus((resumed / "cases" / "ice_b10.status").string()));

    const std::string resume_log = (TempDir() / (folder + ".resume.log")).string();
    EXPECT_EQ(
        scoopsim_test::RunScoopsim(
            "sweep " + FastTiny() + " -o " + resumed.string() + " --threads 1 -q", resume_log),
        0)
        << ReadText(resume_log);
    const std::string text = ReadText(resume_log);
    for (const char* done : {"snow_b5 skipped", "snow_b10 skipped", "ice_b5 skipped"})
      EXPECT_NE(text.find(done), std::string::npos) << text;
    ExpectSameData(plain / "table.h5", resumed / "table.h5");
    ExpectSameData(plain / "cases" / "ice_b10.h5", resumed / "cases" / "ice_b10.h5", "sweep");
    // The root attributes of the dig (a pass resumed from a checkpoint wrote start_time 0).
    for (const char* name : {"start_time", "surface", "scoop_mass", "time"}) {
      const double want =
          sim::SavedRun((plain / "cases" / "ice_b10.h5").string()).RootNumber(name, -1);
      EXPECT_GT(want, 0) << name;
      EXPECT_EQ(sim::SavedRun((resumed / "cases" / "ice_b10.h5").string()).RootNumber(name, -1),
                want)
          << name;
    }
    EXPECT_EQ(RootString(resumed / "cases" / "ice_b10.h5", "state_hash"),
              RootString(plain / "cases" / "ice_b10.h5", "state_hash"));
    EXPECT_FALSE(fs::exists(resumed / "cases" / "ice_b10.parts"));
    return text;
  };
  {
    SCOPED_TRACE("killed mid-pass without checkpoints: pass 2 starts again from bed_1");
    const std::string text = kill_and_resume(
        "resumed", "2:0.3", "0", [](const fs::path& parts, const sim::CaseStatus& status) {
          EXPECT_EQ(status.state, "running");
          EXPECT_EQ(status.passes_done, 1);
          EXPECT_TRUE(fs::exists(parts / "bed_1.h5"));
          EXPECT_FALSE(fs::exists(parts / "pass_2.restart.h5"));
          // The killed pass's file is still a readable HDF5 file (SWMR).
          EXPECT_NO_THROW(sim::SavedRun((parts / "pass_2.h5").string()).SceneYaml());
        });
    EXPECT_NE(text.find("(resumed at pass 2)"), std::string::npos) << text;
    EXPECT_EQ(text.find("pass 1:"), std::string::npos) << text;  // pass 1 was not run again
    EXPECT_EQ(text.find("goes on from"), std::string::npos) << text;
  }
  {
    SCOPED_TRACE("killed mid-pass: pass 2 goes on from its last checkpoint");
    const std::string text = kill_and_resume(
        "resumed_checkpoint", "2:0.3", "0.02",
        [](const fs::path& parts, const sim::CaseStatus& status) {
          EXPECT_EQ(status.passes_done, 1);
          EXPECT_GT(status.pass_cpu_s, 0);  // pass 2's CPU time up to its last checkpoint
          // A checkpoint taken within pass 2, after the bed pass 1 left.
          ASSERT_TRUE(fs::exists(parts / "pass_2.restart.h5"));
          const double pass2_start =
              sim::SavedRun((parts / "bed_1.h5").string()).RootNumber("time", 1e9);
          EXPECT_GT(sim::ReadCheckpoint((parts / "pass_2.restart.h5").string()).time, pass2_start);
        });
    EXPECT_NE(text.find("ice_b10 goes on from"), std::string::npos) << text;
    EXPECT_NE(text.find("(resumed at pass 2)"), std::string::npos) << text;
  }
  {
    // Defect: the case file of a first pass resumed from its checkpoint had start_time 0.
    SCOPED_TRACE("killed mid-pass 1: it goes on from its last checkpoint");
    const std::string text = kill_and_resume(
        "resumed_pass1", "1:0.3", "0.02", [](const fs::path& parts, const sim::CaseStatus& status) {
          EXPECT_EQ(status.passes_done, 0);
          EXPECT_TRUE(fs::exists(parts / "pass_1.restart.h5"));
        });
    EXPECT_NE(text.find("ice_b10 goes on from"), std::string::npos) << text;
  }
  {
    SCOPED_TRACE("killed in the pour: it goes on from its last keep");
    const std::string text = kill_and_resume(
        "resumed_pour", "0:0.2", "0.02", [](const fs::path& parts, const sim::CaseStatus& status) {
          EXPECT_EQ(status.passes_done, 0);
          EXPECT_GT(status.bed_cpu_s, 0);  // the pour's CPU time up to its keep
          EXPECT_FALSE(fs::exists(parts / "bed_0.h5"));
          sim::PourPoint point;
          EXPECT_TRUE(sim::ReadPourPoint((parts / "pour.h5").string(),
                                         sim::SavedRun((parts / "pour.h5").string()).SceneYaml(),
                                         &point));
          EXPECT_GT(point.poured, 0);
        });
    EXPECT_NE(text.find("the pour goes on from"), std::string::npos) << text;
  }
  {
    SCOPED_TRACE("SIGTERM mid-pass: stopped, kept, and pass 2 goes on from its restart file");
    const std::string text =
        kill_and_resume("stopped_pass", "2:0.3:TERM", "0.02",
                        [](const fs::path& parts, const sim::CaseStatus& status) {
                          EXPECT_EQ(status.state, "stopped");
                          EXPECT_EQ(status.passes_done, 1);
                          EXPECT_TRUE(fs::exists(parts / "pass_2.restart.h5"));
                        });
    EXPECT_NE(text.find("ice_b10 goes on from"), std::string::npos) << text;
    EXPECT_NE(text.find("(resumed at pass 2)"), std::string::npos) << text;
  }
}

}  // namespace

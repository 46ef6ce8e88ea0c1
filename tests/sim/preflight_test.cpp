// Tests sim/loop/preflight.cpp and the bed file checks of sim/files/bed_io.cpp: each defect of issue 22's
// "every bad input refused, and refused early" is refused with one line that names the file, the
// line (or the dataset) and the key, before any bed is poured or loaded, and the CLI exits 2.
#include "sim/loop/preflight.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "../cli_util.h"
#include "bad_input_util.h"
#include "sim/loop/progress.h"

namespace sim {
namespace {

namespace fs = std::filesystem;
using scoopsim_test::DigSceneText;
using scoopsim_test::SetBedValue;
using scoopsim_test::WriteText;

const fs::path& Dir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("preflight");
  return dir;
}

// The dig scene with `from` replaced by `to` in its text, written as `name`.
std::string WriteScene(const std::string& name, const std::string& bed_file,
                       const std::string& from = "", const std::string& to = "") {
  std::string text = DigSceneText(bed_file);
  if (!from.empty()) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << "test bug: '" << from << "' not in the scene";
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  const fs::path path = Dir() / name;
  WriteText(path, text);
  return path.string();
}

// A fresh copy of the lattice bed (made once) as `name`.
std::string Bed(const std::string& name) {
  static const std::string lattice = [] {
    const std::string bed = (Dir() / "lattice.h5").string();
    scoopsim_test::WriteLatticeBed(WriteScene("lattice.yaml", ""), bed);
    return bed;
  }();
  const std::string copy = (Dir() / name).string();
  fs::copy_file(lattice, copy, fs::copy_options::overwrite_existing);
  return copy;
}

// The InputError Preflight (after LoadScene) throws for `scene`; fails the test when none.
InputError Refusal(const std::string& scene) {
  try {
    Scene loaded = LoadScene(scene);
    Preflight(&loaded, Work::kRun);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "accepted: " << scene;
  return InputError("");
}

// `scoopsim ARGS`: exit status and stderr.
std::string Stderr(const std::string& args, int* status) {
  const std::string err = (Dir() / "stderr.txt").string();
  *status = scoopsim_test::RunScoopsim(args, err);
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// `scoopsim run SCENE` is refused: exit 2, one line on stderr (no bed, no progress line) that
// starts "scoopsim: " + `start`, and no output file.
void ExpectRunRefused(const std::string& scene, const std::string& start) {
  const std::string out = (Dir() / "refused" / "run.h5").string();
  int status = -1;
  const std::string err = Stderr("run " + scene + " -o " + out, &status);
  EXPECT_EQ(status, 2) << err;
  EXPECT_EQ(err.rfind("scoopsim: " + start, 0), 0u) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  EXPECT_FALSE(fs::exists(out));
}

// The good case: the lattice bed under the dig scene passes, with the scene's time step.
TEST(PreflightTest, GoodDigSceneWithItsBedPasses) {
  Bed("good.h5");
  Scene scene = LoadScene(WriteScene("good.yaml", "good.h5"));
  const double dt = scene.time_step;
  const RunForecast f = Preflight(&scene, Work::kRun);
  EXPECT_EQ(f.particles, 1380);
  EXPECT_EQ(f.time_step, dt);
  EXPECT_NEAR(f.surface, 0.096, 1e-9);  // the lattice's top, measured
  EXPECT_FALSE(f.surface_estimated);
  EXPECT_GT(f.steps, 1e4);
}

// Defect: a bed file with NaN/inf positions was accepted (the run simulated nothing for 78 s,
// then blamed the time step). Now refused at load, naming the file, dataset and particle; the
// other state (velocity, force, contact shear, ...) is refused by LoadBed itself.
TEST(PreflightTest, BedFileWithNonFinitePositionIsRefused) {
  for (const double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    const std::string bed = Bed("nan.h5");
    SetBedValue(bed, "/particles/position", 5, 0, bad);
    const InputError e = Refusal(WriteScene("nan.yaml", "nan.h5"));
    EXPECT_EQ(std::string(e.what()).rfind(bed + ": /particles/position: particle 5: expected a "
                                                "finite centre, got [",
                                          0),
              0u)
        << e.what();
  }
  ExpectRunRefused(WriteScene("nan.yaml", "nan.h5"),
                   Dir().string() + "/nan.h5: /particles/position");

  const std::string bed = Bed("nan_v.h5");
  SetBedValue(bed, "/particles/velocity", 7, 2, std::nan(""));
  Scene scene = LoadScene(WriteScene("nan_v.yaml", "nan_v.h5"));
  World world(scene, 1);
  try {
    world.LoadBed(bed);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              bed + ": /particles/velocity: row 7: expected finite values, got [0, 0, nan]");
  }
}

// Defect: a bed file with particles outside the box was accepted. Its centres must lie between
// the side walls and above the floor, and at most the box's height above its open top (a particle
// the scoop flung may be above it).
TEST(PreflightTest, BedFileWithParticleOutsideTheBoxIsRefused) {
  for (const int axis : {0, 1, 2}) {
    const std::string bed = Bed("out.h5");
    SetBedValue(bed, "/particles/position", 9, axis, -0.05);
    const InputError e = Refusal(WriteScene("out.yaml", "out.h5"));
    EXPECT_NE(std::string(e.what()).find("/particles/position: particle 9: expected a centre "
                                         "inside the scene's box [0, 0, 0] .. [0.37, 0.17, 0.2] m"),
              std::string::npos)
        << e.what();
  }
  const std::string above = Bed("above.h5");
  SetBedValue(above, "/particles/position", 9, 2, 0.35);  // 0.15 m above the 0.2 m box's top
  Scene scene = LoadScene(WriteScene("above.yaml", "above.h5"));
  EXPECT_NO_THROW(Preflight(&scene, Work::kRun));
  // More than the box's height above its top (the defect: one at 50 m made the dig's approach
  // start there, 345 s of simulated time).
  const std::string far = Bed("far.h5");
  SetBedValue(far, "/particles/position", 9, 2, 50.0);
  const InputError e = Refusal(WriteScene("far.yaml", "far.h5"));
  EXPECT_NE(std::string(e.what()).find("/particles/position: particle 9: expected a centre at "
                                       "most the box's height above its open top (z <= 0.4 m)"),
            std::string::npos)
      << e.what();
}

// Defect: the time step came from the scene's bed.radius, not from the bed it loads (the same
// 8 mm bed declared as 20 mm ran with a 2.5x larger step: peak |F| 12.1 N instead of 6.7 N,
// exit 0). A bed.radius that does not hold the file's radii is now refused; one that does sets
// a step no larger than the bed's own smallest sphere allows.
TEST(PreflightTest, BedRadiusThatDisagreesWithTheBedFileIsRefused) {
  Bed("r.h5");
  const std::string scene = WriteScene("r20.yaml", "r.h5", "radius: 8.0e-3\n  count: 1450",
                                       "radius: 20.0e-3\n  count: 200");
  const InputError e = Refusal(scene);
  EXPECT_EQ(e.line(), 8);
  EXPECT_EQ(e.key(), "bed.radius");
  EXPECT_EQ(e.got(), "0.02 m");
  EXPECT_NE(e.expected().find("(0.008 m)"), std::string::npos) << e.what();
  ExpectRunRefused(scene, scene + ":8: bed.radius: expected radii that agree with bed.file");
  // A range that holds 8 mm agrees; its step is that of its smallest radius (<= the bed's own).
  Scene range =
      LoadScene(WriteScene("range.yaml", "r.h5", "radius: 8.0e-3", "radius: [6e-3, 9e-3]"));
  EXPECT_EQ(Preflight(&range, Work::kRun).time_step, range.time_step);
  EXPECT_NEAR(range.time_step, 0.75 * LoadScene(WriteScene("r8.yaml", "r.h5")).time_step, 1e-15);
  Refusal(WriteScene("range_hi.yaml", "r.h5", "radius: 8.0e-3", "radius: [9e-3, 1e-2]"));
}

// Defect: `--stop-after nan` was accepted (CLI11's PositiveNumber lets NaN through).
TEST(PreflightTest, StopAfterNanIsRefused) {
  Bed("stop.h5");
  const std::string scene = WriteScene("stop.yaml", "stop.h5");
  for (const char* bad : {"nan", "inf", "-1", "0", "x"}) {
    SCOPED_TRACE(bad);
    int status = -1;
    const std::string err = Stderr("run " + scene + " --stop-after " + bad, &status);
    EXPECT_EQ(status, 2);
    EXPECT_EQ(err, std::string("scoopsim: --stop-after: expected a finite number > 0 (s), got ") +
                       bad + " (see --help)\n");
  }
}

// Defect: `rayleigh_fraction: 1e-300` was accepted and the run could never end. Refused with the
// estimated number of steps, at the key that makes them too many.
TEST(PreflightTest, RunThatCouldNeverEndIsRefusedWithItsStepCount) {
  Bed("steps.h5");
  const InputError e = Refusal(
      WriteScene("rf.yaml", "steps.h5", "rayleigh_fraction: 0.25", "rayleigh_fraction: 1e-300"));
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "time_step.rayleigh_fraction");
  EXPECT_EQ(e.expected(), "a run of at most 1e+10 steps");
  EXPECT_NE(e.note().find("about 1.75e+304 steps of 1.47e-304 s"), std::string::npos) << e.what();
  // A plain run whose duration alone is too long blames the duration.
  const std::string text = DigSceneText("steps.h5");
  WriteText(Dir() / "long.yaml", text.substr(0, text.find("dig:")) + "duration: 1e300\n");
  const InputError d = Refusal((Dir() / "long.yaml").string());
  EXPECT_EQ(d.key(), "duration") << d.what();
}

// Defects: mesh `scale: 1e300` was accepted (progress passed 100% and went on), and a mesh's
// size was found only once the bed had been poured. The scoop is checked against the box at
// load, before any bed: `run` exits 2 at once with no bed made.
TEST(PreflightTest, MeshScaleSoLargeIsRefusedBeforeAnyBed) {
  for (const char* scale : {"1e300", "1000"}) {
    SCOPED_TRACE(scale);
    const std::string scene =
        WriteScene(std::string("scale") + scale + ".yaml", "", "material: aluminium",
                   std::string("material: aluminium, scale: ") + scale);
    const InputError e = Refusal(scene);
    EXPECT_EQ(e.key(), "dig.scoop.scale") << e.what();
    EXPECT_EQ(e.line(), 11);
    ExpectRunRefused(scene, scene + ":11: dig.scoop.scale: expected a scale that makes the scoop");
  }
}

// Counts that cannot fit in memory are refused with what they would need.
TEST(PreflightTest, BedCountThatCannotFitInMemoryIsRefused) {
  std::string text = DigSceneText("");
  text.replace(text.find("max: [0.37, 0.17, 0.2]"), 22, "max: [1e5, 1e5, 1]");
  text.replace(text.find("count: 1450"), 11, "count: 10000000000000");
  WriteText(Dir() / "huge.yaml", text);
  const InputError e = Refusal((Dir() / "huge.yaml").string());
  EXPECT_EQ(e.key(), "bed.count") << e.what();
  EXPECT_NE(e.note().find("it would need about 9.09 PiB"), std::string::npos) << e.what();
}

// Defect: a dig whose blade reaches the floor stopped mid-run as "unstable, lower the time step".
// Refused at load, from the measured surface of a bed file or the estimated one of a bed still
// to be poured; so is a path that drives the scoop through a side wall below the surface.
TEST(PreflightTest, DigPathIntoTheFloorOrThroughAWallIsRefusedAtLoad) {
  Bed("floor.h5");
  const InputError measured =
      Refusal(WriteScene("floor.yaml", "floor.h5", "bite_depth: 0.02", "bite_depth: 0.12"));
  EXPECT_EQ(measured.key(), "dig.bite_depth");
  EXPECT_EQ(measured.expected(), "a path that keeps the scoop above the floor (box.min z = 0 m)");
  // The depth's inputs named: the pass, the bite depth and where the surface comes from.
  EXPECT_NE(measured.note().find("pass 1 cuts 1 x dig.bite_depth = 0.12 m below the surface of "
                                 "bed.file " +
                                 (Dir() / "floor.h5").string() + " at z = 0.096 m"),
            std::string::npos)
      << measured.what();
  const InputError estimated =
      Refusal(WriteScene("floor_pour.yaml", "", "bite_depth: 0.02", "bite_depth: 0.2"));
  EXPECT_EQ(estimated.key(), "dig.bite_depth");
  EXPECT_NE(estimated.note().find("estimated from bed.count 1450 spheres of bed.radius 0.008 m "
                                  "settled over the box's 0.37 x 0.17 m floor"),
            std::string::npos)
      << estimated.what();
  const InputError wall =
      Refusal(WriteScene("wall.yaml", "floor.h5", "start: [0.13, 0.085]", "start: [0.01, 0.085]"));
  EXPECT_EQ(wall.key(), "dig.trajectory.start") << wall.what();
  ExpectRunRefused(WriteScene("floor.yaml", "floor.h5", "bite_depth: 0.02", "bite_depth: 0.12"),
                   (Dir() / "floor.yaml").string() + ":19: dig.bite_depth: expected a path");
}

// Every shipped scene (scenes/shipped.txt) without a bed file passes (those with one name beds
// made by the demo). The list, not the folder: a scene of the user's own in scenes/ is not read.
TEST(PreflightTest, ShippedScenesPass) {
  const fs::path scenes = fs::path(SCOOPSIM_SOURCE_DIR) / "scenes";
  int checked = 0;
  for (const fs::path& path : scoopsim_test::ShippedScenes(scenes)) {
    if (path.filename() == "materials.yaml") continue;
    if (path.parent_path().filename() == "sweeps") continue;
    SCOPED_TRACE(path.string());
    // A table-driven arm's scene loads only once its table is built (TableArm tests cover it).
    std::ifstream text(path);
    const std::string yaml((std::istreambuf_iterator<char>(text)),
                           std::istreambuf_iterator<char>());
    if (yaml.find("wrench: table") != std::string::npos) continue;
    Scene scene = LoadScene(path.string());
    if (!scene.bed.file.empty()) continue;
    EXPECT_NO_THROW(Preflight(&scene, Work::kRun));
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

// scenes/shipped.txt names only files that exist, each once, and, in a git checkout with git on
// the PATH, every scenes/*.yaml that git tracks (`git ls-files`: a user's untracked scene is not
// asked for). Without git the second half is skipped, not failed: a tarball has no index.
TEST(PreflightTest, ShippedListMatchesTheRepository) {
  const fs::path source(SCOOPSIM_SOURCE_DIR);
  const std::vector<fs::path> listed = scoopsim_test::ShippedScenes(source / "scenes");
  ASSERT_GT(listed.size(), 10u) << "scenes/shipped.txt missing or nearly empty";
  std::vector<std::string> names;
  for (const fs::path& path : listed) {
    EXPECT_TRUE(fs::is_regular_file(path))
        << path << " is listed in scenes/shipped.txt but is not a file";
    names.push_back(fs::relative(path, source).string());
  }
  std::vector<std::string> sorted = names;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end())
      << "a path is listed twice in scenes/shipped.txt";

  if (!fs::exists(source / ".git")) GTEST_SKIP() << "not a git checkout";
  const fs::path out = Dir() / "tracked.txt";
  const std::string cmd = "git -C '" + source.string() + "' ls-files -- 'scenes/*.yaml' >'" +
                          out.string() + "' 2>/dev/null";
  if (std::system(cmd.c_str()) != 0) GTEST_SKIP() << "git ls-files did not run";
  std::istringstream tracked(scoopsim_test::ReadText(out));
  int count = 0;
  for (std::string line; std::getline(tracked, line);) {
    ++count;
    EXPECT_NE(std::find(names.begin(), names.end(), line), names.end())
        << line << " is tracked by git but not listed in scenes/shipped.txt";
  }
  EXPECT_GT(count, 10);
}

// A bed.file that does not exist is refused naming the scene, its line and the key (it named
// only the bed file).
TEST(PreflightTest, MissingBedFileNamesTheSceneAndKey) {
  const InputError e = Refusal(WriteScene("nobed.yaml", "no_such_bed.h5"));
  EXPECT_EQ(e.key(), "bed.file") << e.what();
  EXPECT_EQ(e.line(), 10) << e.what();
  EXPECT_NE(std::string(e.what()).find("no_such_bed.h5 (no such file)"), std::string::npos)
      << e.what();
}

// Defect: a scene's stray binary bytes were quoted back raw into the one-line message (a
// terminal showed garbage; a log got invalid UTF-8). They are now written as \xNN.
TEST(PreflightTest, BinaryBytesInAMessageAreEscaped) {
  const fs::path scene = Dir() / "binary.yaml";
  WriteText(scene, std::string("materials: \xFF\xFE\x01junk\n"));
  int status = -1;
  const std::string err = Stderr("check " + scene.string(), &status);
  EXPECT_EQ(status, 2) << err;
  EXPECT_NE(err.find("got \\xFF\\xFE\\x01junk"), std::string::npos) << err;
  EXPECT_EQ(err.find('\xFF'), std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
}

// Defect: a bed file with two coincident particles, or one at 1e30 m/s, passed `check`; the run
// then stopped at its first step blaming the time step. Now refused naming the file and the
// particles: overlap past health.max_overlap of the smaller diameter (the lattice's touching
// spheres overlap by 0), or a particle faster than its radius a step.
TEST(PreflightTest, BedFileWithOverlappingOrFlyingParticlesIsRefused) {
  const std::string overlap = Bed("overlap.h5");
  // Particle 9 moved half a diameter towards particle 10 (its neighbour along x on the lattice).
  SetBedValue(overlap, "/particles/position", 9, 0, 0.008 * 2 * 9 + 0.008 + 0.008);
  InputError e = Refusal(WriteScene("overlap.yaml", "overlap.h5"));
  EXPECT_EQ(e.key(), "bed.file") << e.what();
  EXPECT_NE(std::string(e.what()).find("overlap by 0.5 of the smaller diameter"), std::string::npos)
      << e.what();
  const std::string flying = Bed("flying.h5");
  SetBedValue(flying, "/particles/velocity", 9, 2, 1e30);
  e = Refusal(WriteScene("flying.yaml", "flying.h5"));
  EXPECT_EQ(e.key(), "bed.file") << e.what();
  EXPECT_NE(std::string(e.what()).find("/particles/velocity: particle 9 at 1e+30 m/s"),
            std::string::npos)
      << e.what();
}

// Defect: bed.material was ignored when bed.file was set (a sweep's grid over bed.material on
// one bed file ran snow under the name ice, exit 0). A scene whose bed.material is not that of
// the file's particles is now refused.
TEST(PreflightTest, BedMaterialThatDisagreesWithTheBedFileIsRefused) {
  Bed("m.h5");
  const InputError e = Refusal(WriteScene("m_ice.yaml", "m.h5", "material: snow", "material: ice"));
  EXPECT_EQ(e.key(), "bed.material") << e.what();
  EXPECT_EQ(e.line(), 7) << e.what();
  EXPECT_NE(std::string(e.what()).find("particles (snow), got ice"), std::string::npos) << e.what();
}

// Defect: a scoop mesh of zero-area triangles (coincident corners) was accepted and dug with
// (its edges met the grains: peak |F| 4.7 N against 28.8 N for the real mesh). A mesh with any
// zero-area triangle is now refused at load, naming the count and the first.
TEST(PreflightTest, MeshWithZeroAreaTrianglesIsRefused) {
  const fs::path stl = Dir() / "degenerate.stl";
  std::ofstream(stl) << "solid s\n"
                        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\n"
                        "vertex 0 0.1 0\nendloop\nendfacet\n"
                        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\n"
                        "vertex 0.2 0 0\nendloop\nendfacet\n"
                        "endsolid s\n";
  const std::string scene = WriteScene(
      "degenerate.yaml", "", std::string(SCOOPSIM_SOURCE_DIR) + "/assets/scoop.stl", stl.string());
  try {
    LoadScene(scene);
    ADD_FAILURE() << "accepted: " << scene;
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "dig.scoop.mesh") << e.what();
    EXPECT_NE(std::string(e.what()).find("got 1 of 2 triangles with zero area (the first: "
                                         "triangle 1)"),
              std::string::npos)
        << e.what();
  }
}

// Defect: `-o` could name the run's own scene, materials file or mesh: each was overwritten
// with HDF5, exit 0. Each is now refused before any work, and the file is left as it was.
TEST(PreflightTest, OutputOverTheScenesOwnFilesIsRefused) {
  const fs::path materials = Dir() / "own_materials.yaml";
  fs::copy_file(fs::path(SCOOPSIM_SOURCE_DIR) / "scenes" / "materials.yaml", materials,
                fs::copy_options::overwrite_existing);
  const fs::path mesh = Dir() / "own_scoop.stl";
  fs::copy_file(fs::path(SCOOPSIM_SOURCE_DIR) / "assets" / "scoop.stl", mesh,
                fs::copy_options::overwrite_existing);
  std::string text = DigSceneText("");
  const std::string source = SCOOPSIM_SOURCE_DIR;
  text.replace(text.find(source + "/scenes/materials.yaml"),
               (source + "/scenes/materials.yaml").size(), materials.string());
  text.replace(text.find(source + "/assets/scoop.stl"), (source + "/assets/scoop.stl").size(),
               mesh.string());
  const fs::path scene = Dir() / "own.yaml";
  WriteText(scene, text);
  for (const auto& [output, what] : {std::pair<fs::path, std::string>{scene, "the scene"},
                                     {materials, scene.string() + ": materials"},
                                     {mesh, scene.string() + ": dig.scoop.mesh"}}) {
    SCOPED_TRACE(output.string());
    const auto size = fs::file_size(output);
    for (const char* command : {"run ", "bed "}) {
      int status = -1;
      const std::string err = Stderr(command + scene.string() + " -o " + output.string(), &status);
      EXPECT_EQ(status, 2) << err;
      EXPECT_EQ(err, "scoopsim: " + output.string() + ": -o names the run's own input (" + what +
                         " = " + output.string() + "); give another output file\n");
      EXPECT_EQ(fs::file_size(output), size);
    }
  }
}

// Defect: `run --frames D --every 1e-300` (or render.every: 1e-300) spun for ever, deaf to
// SIGTERM: the next frame's time never advanced. A spacing below the time step, or not a
// finite number > 0, is now refused before any work.
TEST(PreflightTest, FrameSpacingBelowTheTimeStepIsRefused) {
  Bed("f.h5");
  const std::string scene = WriteScene("frames.yaml", "f.h5");
  const std::string frames = (Dir() / "frames").string();
  int status = -1;
  std::string err = Stderr("run " + scene + " -o " + (Dir() / "f_out.h5").string() + " --frames " +
                               frames + " --every 1e-300 --stop-after 0.001",
                           &status);
  EXPECT_EQ(status, 2) << err;
  EXPECT_EQ(err.rfind("scoopsim: --every: expected at least the time step (", 0), 0u) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  err = Stderr("run " + scene + " -o " + (Dir() / "f_out.h5").string() + " --frames " + frames +
                   " --every nan --stop-after 0.001",
               &status);
  EXPECT_EQ(status, 2) << err;
  EXPECT_EQ(err.rfind("scoopsim: --every: expected a finite number > 0 (s), got nan", 0), 0u)
      << err;
  const std::string in_scene = WriteScene("frames_scene.yaml", "f.h5", "sleep: {enabled: true}\n",
                                          "sleep: {enabled: true}\nrender: {every: 1.0e-300}\n");
  err = Stderr("run " + in_scene + " -o " + (Dir() / "f_out.h5").string() + " --frames " + frames +
                   " --stop-after 0.001",
               &status);
  EXPECT_EQ(status, 2) << err;
  EXPECT_EQ(
      err.rfind("scoopsim: " + in_scene + ": render.every: expected at least the time step", 0), 0u)
      << err;
}

// Diagnostics never print non-physical times: the progress clock of a run planned for 1e299 s
// read "ETA -153722867280912930:-8".
TEST(PreflightTest, ProgressClockPrintsOnlyPhysicalTimes) {
  EXPECT_EQ(Clock(3723), "1:02:03");
  EXPECT_EQ(Clock(59.4), "0:59");
  for (const double bad : {1e299, 1e7, -1.0, std::nan(""), HUGE_VAL})
    EXPECT_EQ(Clock(bad), "--:--");
}

// A run that goes on from a kept state at t = 0.5 s of its 1 s, 3e9 particle-steps done: the line
// shows the whole run's time and percent, but the rate and the ETA count only this sitting. A
// fake clock ticks 1 s per update, each update 0.05 s simulated and 1e6 particle-steps: at
// t = 0.7 s the rate is 4e6 / 4 s = 1 M/s, and the ETA, both at the whole sitting's rate and at
// the last 2 s's, is (1 - 0.7) s / (0.05 s/s) = 6 s. Counted from t = 0 and 0 steps, the rate
// would read 751 M/s and the ETA 3.86 s (0.3 * 4 / 0.7 and 6, averaged).
TEST(PreflightTest, ResumedProgressCountsOnlyThisSitting) {
  double now = 100;
  Progress progress("dig", 1.0, false, 1.0, [&now] { return now; });
  progress.Begin(0.5, 3'000'000'000);
  testing::internal::CaptureStderr();
  for (int k = 1; k <= 4; ++k) {
    now += 1.0;
    progress.Update(0.5 + 0.05 * k, 3'000'000'000 + 1'000'000 * k);
  }
  const std::string text = testing::internal::GetCapturedStderr();
  EXPECT_NEAR(progress.eta(), 6.0, 1e-9);
  EXPECT_NE(text.find("dig  70.0%  t 0.7/1 s  elapsed 0:04  ETA 0:06  1 M particle-steps/s"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace sim

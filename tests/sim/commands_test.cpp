// `scoopsim study shape` end to end (sim/runner.cpp RunShapeStudy) on a tiny scene: a 2 cm box
// pushed 15 mm through a sparse layer of clumps, once per built-in template. The file holds one
// group per template with the dig's /scoop rows and the table of spheres, clumps, wall time and
// force; stderr ends with the table. `scoopsim study balovnev` end to end on the same box pushed
// through a shallow bed of spheres, and `scoopsim study particle-size` on that bed at two sizes.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim/studies/balovnev.h"
#include "sim/files/saved_run.h"
#include "sim/studies/commands.h"
#include "sim/studies/size_study.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("study");
  return dir;
}

// The studies run their plot scripts under the environment's SCOOPSIM_PYTHON, else python3 on PATH
// (sim::PythonInterpreter); a test that plots names the Python with numpy, h5py and matplotlib
// that CMake's SCOOPSIM_PYTHON gives (tests/CMakeLists.txt), as a python3 first on PATH may lack
// them. The CLI it runs inherits it.
void UseTestPython() { setenv("SCOOPSIM_PYTHON", SCOOPSIM_TEST_PYTHON, 1); }

// An ASCII STL of the box [-h, h] x [-h, h] x [-t, t] (12 facets, outward normals).
void WriteBoxStl(const fs::path& path, double h, double t) {
  std::ofstream out(path);
  out << "solid tool\n";
  const double c[8][3] = {{-h, -h, -t}, {h, -h, -t}, {h, h, -t}, {-h, h, -t},
                          {-h, -h, t},  {h, -h, t},  {h, h, t},  {-h, h, t}};
  const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  for (const auto& tri : f) {
    out << "facet normal 0 0 0\nouter loop\n";
    for (int v : tri) out << "vertex " << c[v][0] << " " << c[v][1] << " " << c[v][2] << "\n";
    out << "endloop\nendfacet\n";
  }
  out << "endsolid tool\n";
}

constexpr double kMaxOverlap = 0.15;  // WriteScene's health.max_overlap

// A scene of the 2 cm box tool (tool.stl) buried at the start and pushed 15 mm at 0.3 m/s along
// x: the box is 0.06 x 0.05 x box_z m, `bed` the bed block's keys, `dig` more keys of the dig
// block, `tail` more top-level keys.
std::string WriteToolScene(const std::string& name, double box_z, const std::string& bed,
                           const std::string& dig, const std::string& tail) {
  WriteBoxStl(TempDir() / "tool.stl", 0.01, 0.002);
  const fs::path path = TempDir() / name;
  std::ofstream(path) << "materials: " << SCOOPSIM_SOURCE_DIR << "/scenes/materials.yaml\n"
                      << "gravity: [0, 0, -9.81]\ntime_step: {rayleigh_fraction: 0.3}\n"
                      << "box: {min: [0, 0, 0], max: [0.06, 0.05, " << box_z
                      << "], wall_material: wall}\nbed:\n"
                      << bed << R"(dig:
  scoop: {mesh: tool.stl, material: aluminium, cavity: {min: [-0.001, -0.001, -0.001], max: [0.001, 0.001, 0.001]}}
  trajectory:
    preset: none
    start: [0.018, 0.025]
    initial_pitch: 0
    linear: {start: 0, speed: 0.3, distance: 0.015}
  passes: 1
  start_buried: true
  interval: 1.0e-3
)" << dig << "sleep: {enabled: true}\n"
                      << tail;
  return path.string();
}

// A sparse layer of `count` ice clumps, the tool spanning it.
std::string WriteScene(int count = 60, const std::string& name = "tiny_shape.yaml") {
  return WriteToolScene(
      name, 0.05,
      "  material: ice\n  clump: tetra4\n  count: " + std::to_string(count) +
          "\n  seed: 4\n  fill_fraction: 0.3\n"
          "  settle: {kinetic_energy: 1.0, max_time: 0.5}\n",
      "  bite_depth: 0.004\n"
      "  surface: 0.006   # the layers are one clump deep: the tool spans z 2..6 mm\n",
      "health: {max_overlap: 0.15}\n");
}

std::vector<double> ReadDoubles(hid_t file, const std::string& name, hsize_t* rows,
                                hsize_t* width) {
  std::vector<double> out;
  const hid_t d = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(d, 0) << name;
  if (d < 0) return out;
  const hid_t space = H5Dget_space(d);
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
  *rows = dims[0];
  *width = rank == 2 ? dims[1] : 1;
  out.resize(dims[0] * *width);
  if (!out.empty()) H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(space);
  H5Dclose(d);
  return out;
}

double ReadAttribute(hid_t file, const std::string& group, const std::string& name) {
  double value = -1;
  const hid_t a = H5Aopen_by_name(file, group.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(a, 0) << group << " " << name;
  if (a < 0) return value;
  H5Aread(a, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(a);
  return value;
}

TEST(ShapeStudyTest, RunsEveryTemplateIntoOneFile) {
  const std::string scene = WriteScene();
  const std::string out = (TempDir() / "study.h5").string();
  const std::string log = (TempDir() / "study.log").string();
  ASSERT_EQ(
      scoopsim_test::RunScoopsim("study shape " + scene + " -o " + out + " --threads 1 -q", log), 0)
      << std::ifstream(log).rdbuf();
  const hid_t file = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const char* names[] = {"tetra1", "tetra4", "tetra8", "tetra12"};
  const double spheres_per_clump[] = {1, 4, 8, 12};
  hsize_t rows = 0, width = 0;
  const std::vector<double> table_spheres =
      ReadDoubles(file, "/table/spheres_per_clump", &rows, &width);
  ASSERT_EQ(rows, 4u);
  const std::vector<double> table_wall = ReadDoubles(file, "/table/dig_wall_s", &rows, &width);
  const std::vector<double> table_peak = ReadDoubles(file, "/table/peak_force", &rows, &width);
  const std::vector<double> table_overlap = ReadDoubles(file, "/table/peak_overlap", &rows, &width);
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(names[k]);
    const std::string g = std::string("/") + names[k];
    EXPECT_EQ(table_spheres[k], spheres_per_clump[k]);
    EXPECT_EQ(ReadAttribute(file, g, "spheres_per_clump"), spheres_per_clump[k]);
    const double clumps = ReadAttribute(file, g, "clumps");
    EXPECT_GT(clumps, 10);
    EXPECT_EQ(ReadAttribute(file, g, "spheres"), clumps * spheres_per_clump[k]);
    EXPECT_GT(table_wall[k], 0.0);
    EXPECT_EQ(ReadAttribute(file, g, "dig_wall_s"), table_wall[k]);
    EXPECT_EQ(ReadAttribute(file, g, "peak_force"), table_peak[k]);
    // A bed under gravity has contacts, so some overlap; below the scene's stop limit.
    EXPECT_GT(table_overlap[k], 0.0);
    EXPECT_LT(table_overlap[k], kMaxOverlap);
    EXPECT_EQ(ReadAttribute(file, g, "peak_overlap"), table_overlap[k]);
    // The dig's rows, as a run's /scoop/.
    const std::vector<double> t = ReadDoubles(file, g + "/scoop/time", &rows, &width);
    EXPECT_GE(rows, 40u);  // 0.05 s at 1 ms
    const std::vector<double> f = ReadDoubles(file, g + "/scoop/force_body", &rows, &width);
    EXPECT_EQ(width, 3u);
    EXPECT_EQ(rows, t.size());
    double peak = 0;
    for (size_t r = 0; r < rows; ++r)
      peak = std::max(peak, std::sqrt(f[3 * r] * f[3 * r] + f[3 * r + 1] * f[3 * r + 1] +
                                      f[3 * r + 2] * f[3 * r + 2]));
    EXPECT_GT(peak, 0.0) << "the tool touched the bed";
  }
  // The finer the clumps, the smaller the time step (paper eq. 4, Table 3).
  const std::vector<double> dt = ReadDoubles(file, "/table/time_step", &rows, &width);
  EXPECT_GT(dt[1], dt[2]);
  EXPECT_GT(dt[2], dt[3]);
  H5Fclose(file);
  // The table on stderr, one row per template.
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  for (const char* name : names)
    EXPECT_NE(text.str().find(std::string("| ") + name + " |"), std::string::npos) << text.str();
}

// --beds DIR keeps each template's bed; a later study loads it only when the bed was made from
// the same scene text, else it makes the bed again (a stale bed of another count would silently
// change the study).
TEST(ShapeStudyTest, CachedBedIsReusedOnlyForTheSameScene) {
  const fs::path beds = TempDir() / "beds";
  auto study = [&](const std::string& scene, const std::string& tag, std::string* text) {
    const std::string out = (TempDir() / ("cache_" + tag + ".h5")).string();
    const std::string log = (TempDir() / ("cache_" + tag + ".log")).string();
    EXPECT_EQ(
        scoopsim_test::RunScoopsim("study shape " + scene + " -o " + out +
                                       " --templates tetra1 --threads 1 -q --beds " + beds.string(),
                                   log),
        0);
    std::stringstream s;
    s << std::ifstream(log).rdbuf();
    *text = s.str();
    const hid_t file = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    EXPECT_GE(file, 0);
    if (file < 0) return -1.0;
    const double clumps = ReadAttribute(file, "/tetra1", "clumps");
    H5Fclose(file);
    return clumps;
  };
  std::string first, second, third;
  const std::string scene = WriteScene(60, "cache_a.yaml");
  // (a tetra1 bed holds the solid volume of `count` four-sphere clumps, so more than `count`)
  const double made = study(scene, "first", &first);
  EXPECT_GT(made, 60);
  ASSERT_TRUE(fs::exists(beds / "tetra1.h5"));
  EXPECT_EQ(first.find("making it again"), std::string::npos) << first;
  EXPECT_EQ(study(scene, "second", &second), made);
  EXPECT_EQ(second.find("making it again"), std::string::npos) << second;
  // Another count: the cached bed is not this scene's, so the bed is made again and is larger.
  EXPECT_GT(study(WriteScene(70, "cache_b.yaml"), "third", &third), made);
  EXPECT_NE(third.find("tetra1.h5 was made from another scene; making it again"), std::string::npos)
      << third;
}

TEST(ShapeStudyTest, UnknownTemplateIsBadInput) {
  const std::string scene = WriteScene();
  const std::string log = (TempDir() / "bad.log").string();
  EXPECT_EQ(
      scoopsim_test::RunScoopsim("study shape " + scene + " -o " + (TempDir() / "x.h5").string() +
                                     " --templates tetra4,tetra7 -q",
                                 log),
      2);
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  EXPECT_NE(text.str().find("--templates: expected names among tetra1, tetra4, tetra8, tetra12, "
                            "got tetra7"),
            std::string::npos)
      << text.str();
}

// A study keeps its threads fixed, so it does not offer the governor's --fixed-threads: CLI11
// refuses the unknown flag with exit 2 (only `bed` and `run` take it, tests/sim/world_test.cpp).
TEST(ShapeStudyTest, FixedThreadsIsNotAStudyOption) {
  const std::string scene = WriteScene();
  const std::string log = (TempDir() / "fixed.log").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("study shape " + scene + " -o " +
                                           (TempDir() / "x.h5").string() + " --fixed-threads -q",
                                       log),
            2);
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  EXPECT_NE(text.str().find("--fixed-threads"), std::string::npos) << text.str();
}

// The tool pushed with its bottom 12 mm under the surface through ~500 sand spheres of 2.5 mm (a
// bed ~24 mm deep: deep enough for the solid fraction's box, 6 radii).
std::string WriteSphereScene() {
  return WriteToolScene(
      "tiny_balovnev.yaml", 0.08,
      "  material: sand\n  radius: 2.5e-3\n  count: 500\n  seed: 4\n"
      "  fill_fraction: 0.45\n  settle: {kinetic_energy: 1.0e-6, max_time: 0.3}\n",
      "  bite_depth: 0.012\n", "");
}

// The study's CSV against its oracles: one row per /scoop/ row; the blade tip is the box's +x
// face centre (h, 0, 0) carried by the pose (level: l_scoop x -> world x), so tip = position +
// (h, 0, 0) to 1e-12 m, h as the STL stores it (a float: 0.01f); depth = max(0, surface - tip_z)
// (1e-12 m); the DEM's horizontal and downward forces are -F_world.x and -F_world.z of the run
// file, exactly (the CSV writes 17 digits); Balovnev's columns are sim::Balovnev at the row's depth
// with the soil the CSV's header states (gamma = rho_bulk g; relative 1e-12), the lander's columns
// sim::BalovnevLander at that depth (its own gamma and q). The table is printed,
// the PNG drawn.
TEST(BalovnevStudyTest, CsvMatchesTheRunAndTheModel) {
  UseTestPython();
  const std::string scene = WriteSphereScene();
  const std::string out = (TempDir() / "balovnev.h5").string();
  const std::string table = (TempDir() / "balovnev.txt").string();
  const std::string log = (TempDir() / "balovnev.log").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim(
                "study balovnev " + scene + " -o " + out + " --threads 1 -q > " + table, log),
            0)
      << scoopsim_test::ReadText(log);
  const std::string printed = scoopsim_test::ReadText(table);
  EXPECT_NE(printed.find("| t [s] | rho [mm] | depth [mm] | DEM F_h [N] | textbook F_h [N] | "
                         "textbook A_II F_h [N] | lander F_h [N] |"),
            std::string::npos)
      << printed;
  EXPECT_NE(printed.find("| mean, rows cut |"), std::string::npos) << printed;
  EXPECT_TRUE(fs::exists(TempDir() / "balovnev.balovnev.png"));

  const hid_t file = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  hsize_t rows = 0, width = 0;
  const std::vector<double> force = ReadDoubles(file, "/scoop/force_world", &rows, &width);
  const std::vector<double> pose = ReadDoubles(file, "/scoop/pose", &rows, &width);
  H5Fclose(file);
  ASSERT_GE(rows, 40u);  // 0.05 s at 1 ms

  std::ifstream csv(TempDir() / "balovnev.balovnev.csv");
  std::string line;
  double gamma = 0;
  std::vector<std::vector<double>> data;
  while (std::getline(csv, line)) {
    if (line.rfind("# rho_bulk", 0) == 0) {
      const size_t at = line.find("gamma ");
      ASSERT_NE(at, std::string::npos) << line;
      gamma = std::stod(line.substr(at + 6));
      continue;
    }
    if (line.empty() || line[0] == '#' || line.rfind("time,", 0) == 0) continue;
    std::vector<double> v;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(std::stod(field));
    ASSERT_EQ(v.size(), 16u) << line;
    data.push_back(v);
  }
  ASSERT_EQ(data.size(), rows);
  ASSERT_GT(gamma, 0.3 * 2650 * 9.81);  // a solid fraction in (0.3, 0.7): a loose bed
  ASSERT_LT(gamma, 0.7 * 2650 * 9.81);
  sim::BalovnevSoil soil;
  soil.unit_weight = gamma;
  int cut = 0;
  for (size_t r = 0; r < rows; ++r) {
    SCOPED_TRACE(r);
    const std::vector<double>& v = data[r];
    EXPECT_NEAR(v[3], pose[7 * r] + static_cast<double>(0.01f), 1e-12);
    EXPECT_NEAR(v[5], pose[7 * r + 2], 1e-12);
    EXPECT_NEAR(v[7], std::max(0.0, v[6] - v[5]), 1e-12);
    EXPECT_EQ(v[8], -force[3 * r]);
    EXPECT_EQ(v[9], -force[3 * r + 2]);
    const sim::BalovnevTool tool;
    const sim::BalovnevForce split =
        sim::Balovnev(v[7], tool, soil, false, sim::BalovnevBranch::kSplit);
    const sim::BalovnevForce plugin =
        sim::Balovnev(v[7], tool, soil, false, sim::BalovnevBranch::kPlugin);
    EXPECT_NEAR(v[10], split.horizontal, 1e-12 * split.horizontal);
    EXPECT_NEAR(v[11], split.vertical, 1e-12 * split.vertical);
    EXPECT_NEAR(v[12], plugin.horizontal, 1e-12 * plugin.horizontal);
    EXPECT_NEAR(v[13], plugin.vertical, 1e-12 * plugin.vertical);
    // The lander plugin's variant: its own constants whatever the bed (sim::BalovnevLander).
    const sim::BalovnevForce lander = sim::BalovnevLander(v[7], tool, soil);
    EXPECT_NEAR(v[14], lander.horizontal, 1e-12 * lander.horizontal);
    EXPECT_NEAR(v[15], lander.vertical, 1e-12 * lander.vertical);
    if (v[7] > 0) ++cut;
  }
  // The tip, 10 mm under the mean surface, lies under the local one (grains of 5 mm) on most rows.
  EXPECT_GT(cut, static_cast<int>(rows) / 2);
}

// --model lander: the table shows the DEM and the lander plugin's variant only (the textbook
// columns stay in the CSV); an unknown model is refused with exit 2.
TEST(BalovnevStudyTest, ModelChoosesTheVariantShown) {
  const std::string scene = WriteSphereScene();
  const std::string out = (TempDir() / "balovnev_lander.h5").string();
  const std::string table = (TempDir() / "balovnev_lander.txt").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("study balovnev " + scene + " -o " + out +
                                       " --threads 1 -q --no-plot --model lander > " + table),
            0);
  const std::string printed = scoopsim_test::ReadText(table);
  EXPECT_NE(printed.find("| DEM F_h [N] | lander F_h [N] | DEM F_v down [N] | lander F_v [N] |"),
            std::string::npos)
      << printed;
  EXPECT_EQ(printed.find("textbook"), std::string::npos) << printed;
  EXPECT_EQ(scoopsim_test::RunScoopsim("study balovnev " + scene + " -o " + out + " --model nope",
                                       (TempDir() / "balovnev_model.log").string()),
            2);
}

// Bad input: delta above phi (Balovnev's psi is undefined there) is one line, exit 2, before any
// work.
TEST(BalovnevStudyTest, DeltaAbovePhiIsBadInput) {
  const std::string scene = WriteSphereScene();
  const std::string log = (TempDir() / "balovnev_bad.log").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("study balovnev " + scene + " -o " +
                                           (TempDir() / "bad.h5").string() +
                                           " --phi-deg 30 --delta-deg 35 -q",
                                       log),
            2);
  const std::string text = scoopsim_test::ReadText(log);
  EXPECT_NE(text.find("study balovnev: --delta-deg: expected a value in [0, --phi-deg], got 35"),
            std::string::npos)
      << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_FALSE(fs::exists(TempDir() / "bad.h5"));
}

// sim::RunPlotScript runs PythonInterpreter() ToolsDir()/SCRIPT ARGS: a stand-in interpreter (a
// shell script) given as SCOOPSIM_PYTHON writes down the arguments it got, each whole (a space
// and a quote in them); the source tree's tools/ for this binary, which is not installed. An
// interpreter that fails (/bin/false) is a failed plot; an empty or unset SCOOPSIM_PYTHON means
// python3 as PATH finds it.
TEST(RunPlotScriptTest, RunsTheScriptUnderScoopsimPython) {
  const fs::path fake = TempDir() / "fake python.sh";
  const fs::path record = TempDir() / "fake_python.args";
  std::ofstream(fake) << "#!/bin/sh\nprintf '%s\\n' \"$@\" > '" << record.string() << "'\n";
  fs::permissions(fake, fs::perms::owner_all);
  setenv("SCOOPSIM_PYTHON", fake.c_str(), 1);
  EXPECT_EQ(sim::PythonInterpreter(), fake.string());
  EXPECT_EQ(sim::ToolsDir(), std::string(SCOOPSIM_SOURCE_DIR) + "/tools");
  EXPECT_TRUE(sim::RunPlotScript("plot_balovnev.py", {"a b.csv", "-o", "it's.png"}));
  EXPECT_EQ(scoopsim_test::ReadText(record),
            std::string(SCOOPSIM_SOURCE_DIR) + "/tools/plot_balovnev.py\na b.csv\n-o\nit's.png\n");
  setenv("SCOOPSIM_PYTHON", "/bin/false", 1);
  EXPECT_FALSE(sim::RunPlotScript("plot_balovnev.py", {"x.csv"}));
  setenv("SCOOPSIM_PYTHON", "", 1);
  EXPECT_EQ(sim::PythonInterpreter(), "python3");
  unsetenv("SCOOPSIM_PYTHON");
  EXPECT_EQ(sim::PythonInterpreter(), "python3");
}

// `study particle-size` end to end on the sphere scene (5 mm sand spheres) at 5 and 6 mm, two
// beds each (four cases, ~3 s): the cases' files, DIR/size_study.csv (its '#' lines, header and
// one row per size, the reference's MPE 0), the peaks in it against the case files read again
// (sim::MakeSizeCurve, the default 0.05 s window; the CSV's 9 digits: relative 1e-8), the table,
// the three PNGs; a second run (-o DIR/./) skips every case and writes the same CSV.
TEST(SizeStudyTest, TwoSizesTwoBedsEndToEnd) {
  UseTestPython();
  const std::string scene = WriteSphereScene();
  const fs::path dir = TempDir() / "size";
  const std::string stdout_file = (TempDir() / "size.txt").string();
  const std::string log = (TempDir() / "size.log").string();
  const std::string options = " --sizes 5,6 --beds 2 --threads 1 -q";
  const std::string command =
      "study particle-size " + scene + " -o " + dir.string() + options + " > " + stdout_file;
  ASSERT_EQ(scoopsim_test::RunScoopsim(command, log), 0) << scoopsim_test::ReadText(log);
  const std::string printed = scoopsim_test::ReadText(stdout_file);
  EXPECT_NE(printed.find("| d [mm] | beds | peak |F| [N] |"), std::string::npos) << printed;
  EXPECT_NE(printed.find("verdict (eq. 7)"), std::string::npos) << printed;
  for (const char* png : {"size_force.png", "size_stack.png", "size_mpe.png"})
    EXPECT_TRUE(fs::exists(dir / png)) << png;
  EXPECT_TRUE(fs::exists(dir / "size_study.sweep.yaml"));
  EXPECT_TRUE(fs::exists(dir / "size_curves.csv"));

  const std::string csv = scoopsim_test::ReadText(dir / "size_study.csv");
  EXPECT_NE(csv.find("\n# verdict: largest_within_20pct_mm="), std::string::npos) << csv;
  EXPECT_NE(csv.find("\n# crossing: mpe_20pct_mm="), std::string::npos) << csv;
  EXPECT_NE(printed.find("where |MPE| reaches 20% (linear in d"), std::string::npos) << printed;
  EXPECT_NE(csv.find("\n# smoothing: centred moving mean over 0.05 s"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\n# reference: the finest size, 5 mm"), std::string::npos) << csv;
  std::vector<std::vector<double>> rows;
  std::stringstream lines(csv);
  bool header = false;
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      EXPECT_EQ(line, sim::SizeCsvHeader());
      header = true;
      continue;
    }
    std::vector<double> v;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(std::stod(field));
    ASSERT_EQ(v.size(), 16u) << line;
    rows.push_back(v);
  }
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][0], 5);
  EXPECT_EQ(rows[1][0], 6);
  EXPECT_EQ(rows[0][5], 0);   // mpe_force_pct of the reference
  EXPECT_EQ(rows[0][11], 0);  // mpe_torque_pct
  for (size_t k = 0; k < 2; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(rows[k][1], 2);
    double force = 0, torque = 0;
    for (int bed = 1; bed <= 2; ++bed) {
      const std::string name = "d" + std::string(k == 0 ? "5" : "6") + "_b" + std::to_string(bed);
      const sim::SavedRun run((dir / "cases" / (name + ".h5")).string());
      EXPECT_GT(run.RootNumber("sweep_bed_cpu_s", 0), 0) << name;
      EXPECT_GT(run.RootNumber("sweep_cpu_s", 0), 0) << name;
      const sim::SizeCurve c = sim::MakeSizeCurve(run.Scoop(), 0.05);
      force += c.peak_force / 2;
      torque += c.peak_torque / 2;
    }
    EXPECT_GT(force, 0);
    EXPECT_NEAR(rows[k][2], force, 1e-8 * force);
    EXPECT_NEAR(rows[k][8], torque, 1e-8 * torque);
    EXPECT_GT(rows[k][15], 0);  // cpu_s_mean
  }

  // Again, the folder spelled otherwise: every case skipped, the same table.
  const std::string log2 = (TempDir() / "size2.log").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("study particle-size " + scene + " -o " + dir.string() +
                                           "/./" + options + " --no-plot > /dev/null",
                                       log2),
            0)
      << scoopsim_test::ReadText(log2);
  const std::string again = scoopsim_test::ReadText(log2);
  size_t skipped = 0;
  for (size_t at = again.find("skipped"); at != std::string::npos;
       at = again.find("skipped", at + 1))
    ++skipped;
  EXPECT_EQ(skipped, 4u) << again;
  EXPECT_EQ(scoopsim_test::ReadText(dir / "size_study.csv"), csv);
}

// A study split in two runs (`--prior`): 5 and 6 mm in one run (one bed each), then 6 mm alone
// with the first run's size_study.csv as --prior gives the same rows (its 5 mm row read back from
// the CSV's 9 digits: every column but the measured CPU within 1e-6 relative) and a '# prior:' line
// naming 5 mm; --sizes 6 alone without --prior is one line and exit 2.
TEST(SizeStudyTest, SplitRunWithPriorGivesTheSameRows) {
  const std::string scene = WriteSphereScene();
  const fs::path whole = TempDir() / "size_whole", part = TempDir() / "size_part";
  const std::string log = (TempDir() / "size_split.log").string();
  const std::string options = " --beds 1 --threads 1 -q --no-plot > /dev/null";
  ASSERT_EQ(
      scoopsim_test::RunScoopsim(
          "study particle-size " + scene + " -o " + whole.string() + " --sizes 5,6" + options, log),
      0)
      << scoopsim_test::ReadText(log);
  const std::string prior = (whole / "size_study.csv").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("study particle-size " + scene + " -o " + part.string() +
                                           " --sizes 6 --prior " + prior + options,
                                       log),
            0)
      << scoopsim_test::ReadText(log);
  const auto rows_of = [](const std::string& csv) {
    std::vector<std::vector<double>> rows;
    std::stringstream lines(csv);
    for (std::string line; std::getline(lines, line);) {
      if (line.empty() || line[0] == '#' || line == sim::SizeCsvHeader()) continue;
      std::vector<double> v;
      std::stringstream fields(line);
      for (std::string field; std::getline(fields, field, ',');) v.push_back(std::stod(field));
      rows.push_back(v);
    }
    return rows;
  };
  const std::string part_csv = scoopsim_test::ReadText(part / "size_study.csv");
  EXPECT_NE(part_csv.find("\n# prior: sizes_mm=5 from " + prior), std::string::npos) << part_csv;
  const auto a = rows_of(scoopsim_test::ReadText(prior)), b = rows_of(part_csv);
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  for (size_t r = 0; r < 2; ++r) {
    ASSERT_EQ(b[r].size(), 16u);
    for (size_t k = 0; k < 15; ++k)  // not cpu_s_mean (15): measured, run by run
      EXPECT_NEAR(b[r][k], a[r][k], 1e-6 * std::max(1.0, std::abs(a[r][k]))) << r << "," << k;
  }
  EXPECT_FALSE(fs::exists(part / "cases" / "d5_b1.h5"));  // 5 mm was not run again

  const std::string bad = (TempDir() / "size_split_bad.log").string();
  EXPECT_EQ(
      scoopsim_test::RunScoopsim("study particle-size " + scene + " -o " +
                                     (TempDir() / "size_one").string() + " --sizes 6" + options,
                                 bad),
      2);
  const std::string text = scoopsim_test::ReadText(bad);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("--sizes"), std::string::npos) << text;
}

}  // namespace

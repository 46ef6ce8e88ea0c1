// `scoopsim study shape` end to end (sim/runner.cpp RunShapeStudy) on a tiny scene: a 2 cm box
// pushed 15 mm through a sparse layer of clumps, once per built-in template. The file holds one
// group per template with the dig's /scoop rows and the table of spheres, clumps, wall time and
// force; stderr ends with the table.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("study");
  return dir;
}

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

std::string WriteScene(int count = 60, const std::string& name = "tiny_shape.yaml") {
  WriteBoxStl(TempDir() / "tool.stl", 0.01, 0.002);
  const fs::path path = TempDir() / name;
  std::ofstream(path) << "materials: " << SCOOPSIM_SOURCE_DIR << "/scenes/materials.yaml\n"
                      << R"(gravity: [0, 0, -9.81]
time_step: {rayleigh_fraction: 0.3}
box: {min: [0, 0, 0], max: [0.06, 0.05, 0.05], wall_material: wall}
bed:
  material: ice
  clump: tetra4
  count: )" << count << R"(
  seed: 4
  fill_fraction: 0.3
  settle: {kinetic_energy: 1.0, max_time: 0.5}
dig:
  scoop: {mesh: tool.stl, material: aluminium, cavity: {min: [-0.001, -0.001, -0.001], max: [0.001, 0.001, 0.001]}}
  trajectory:
    preset: none
    start: [0.018, 0.025]
    initial_pitch: 0
    linear: {start: 0, speed: 0.3, distance: 0.015}
  passes: 1
  bite_depth: 0.004
  surface: 0.006                 # the layers are one clump deep: the tool spans z 2..6 mm
  start_buried: true
  interval: 1.0e-3
health: {max_overlap: 0.15}
sleep: {enabled: true}
)";
  return path.string();
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
    EXPECT_EQ(scoopsim_test::RunScoopsim("study shape " + scene + " -o " + out +
                                             " --templates tetra1 --threads 1 -q --beds " +
                                             beds.string(),
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
  EXPECT_NE(third.find("tetra1.h5 was made from another scene; making it again"),
            std::string::npos)
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

}  // namespace

// The wrench table (sim/files/wrench_table.cpp) on synthetic case files, no DEM: two materials, two
// bite depths, two passes, each pass's wrench a known linear function of rho. Closed forms: the
// table at a grid node between two rows is the line through them (exact for a linear wrench, to
// rounding: 1e-12 relative); Query at a grid node and a stored bite depth returns the stored
// sample bit for bit; between nodes it is the linear blend of the two (to rounding); out of the
// domain it throws OutOfTableDomain, or clamps when asked.
#include "sim/files/wrench_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim/files/h5_output.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
using sim::OutOfTableDomain;
using sim::WrenchTable;

constexpr double kRowStep = 0.0025;  // rho between rows [m]: not every grid node is a row
constexpr double kRhoEnd = 0.2;      // rho of the last row of each pass [m]
constexpr int kPasses = 2;

// The wrench of component q (0..11: force_body, torque_body, force_scoop, torque_scoop, x y z
// each) of a case at rho: a + k rho, different for every material, bite depth, pass, component.
double Wrench(int material, double bite, int pass, int q, double rho) {
  const double a = 1.0 + material + 100 * bite + 0.5 * pass + 0.1 * q;
  const double k = -3.0 + 2 * material + 50 * bite + pass + 0.25 * q;
  return a + k * rho;
}

// A case file as a sweep writes it: scene text, /scoop/ rows. Each pass: rows before first
// contact (contacts 0, junk wrench), the contact rows rho = 0, kRowStep, ..., kRhoEnd, then rows
// where the scoop moves back along the trench (rho falling, junk wrench) that the running
// maximum leaves out.
// `sets` are appended to its scene text as the command line's overrides; with `cell`, the
// attributes a sweep writes from the case's validated scene (sim::WriteTableCell).
void WriteCase(const fs::path& dir, const std::string& name, const std::string& material,
               double bite, const std::string& sets = "", const sim::Scene* cell = nullptr) {
  const int m = material == "snow" ? 0 : 1;
  const std::string scene =
      "materials: materials.yaml\nbed: {material: " + material +
      ", radius: 0.008, count: 10}\ndig: {bite_depth: " + std::to_string(bite) + ", passes: 2}\n" +
      sets;
  sim::H5Output out((dir / "cases" / (name + ".h5")).string(), scene, "test");
  if (cell != nullptr) sim::WriteTableCell(*cell, &out);
  double t = 0;
  const auto row = [&](int pass, double rho, double contacts, bool junk) {
    const double p = pass;
    out.AppendRow("/scoop/time", &t, 1);
    out.AppendRow("/scoop/pass", &p, 1);
    out.AppendRow("/scoop/rho", &rho, 1);
    out.AppendRow("/scoop/rho_path", &rho, 1);  // the same: these tests are of the resampling
    out.AppendRow("/scoop/contacts", &contacts, 1);
    const char* names[4] = {"/scoop/force_body", "/scoop/torque_body", "/scoop/force_scoop",
                            "/scoop/torque_scoop"};
    for (int s = 0; s < 4; ++s) {
      double v[3];
      for (int k = 0; k < 3; ++k) v[k] = junk ? 1e6 : Wrench(m, bite, pass, 3 * s + k, rho);
      out.AppendRow(names[s], v, 3);
    }
    t += 1e-3;
  };
  for (int pass = 1; pass <= kPasses; ++pass) {
    for (int i = 0; i < 5; ++i) row(pass, 0.0, 0, true);
    const int n = static_cast<int>(std::lround(kRhoEnd / kRowStep));
    for (int i = 0; i <= n; ++i) row(pass, i * 2.5 / 1e3, 3, false);  // i * kRowStep, rounded once
    for (int i = 1; i <= 5; ++i) row(pass, kRhoEnd - i * kRowStep, 3, true);
  }
  out.Close();
}

class WrenchTableTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = scoopsim_test::ProcessTempDir("wrench_table");
    WriteCase(dir_, "snow_b5", "snow", 0.005);
    WriteCase(dir_, "snow_b10", "snow", 0.01);
    WriteCase(dir_, "ice_b5", "ice", 0.005);
    WriteCase(dir_, "ice_b10", "ice", 0.01);
    table_path_ = (dir_ / "table.h5").string();
    sim::WrenchTableOptions options;
    options.rho_step_mm = 1;  // a node every mm: node r is rho = r mm below
    sim::BuildWrenchTable(dir_.string(), table_path_, options);
  }
  static fs::path dir_;
  static std::string table_path_;
};
fs::path WrenchTableTest::dir_;
std::string WrenchTableTest::table_path_;

TEST_F(WrenchTableTest, AxesFollowTheCases) {
  const WrenchTable table(table_path_);
  EXPECT_EQ(table.materials(), (std::vector<std::string>{"snow", "ice"}));  // by lander id
  EXPECT_EQ(table.material_ids(), (std::vector<int>{1, 2}));
  EXPECT_EQ(table.bite_depths(), (std::vector<double>{0.005, 0.01}));
  EXPECT_EQ(table.passes(), (std::vector<int>{1, 2}));
  ASSERT_EQ(table.rho().size(), 451u);  // 0..450 mm every 1 mm
  EXPECT_EQ(table.rho()[120], 0.12);
  EXPECT_DOUBLE_EQ(table.rho_step(), 1e-3);
  EXPECT_EQ(table.rho_definition(), sim::RhoDefinition::kPath);
  for (int m = 0; m < 2; ++m)
    for (int b = 0; b < 2; ++b)
      for (int p = 0; p < 2; ++p) EXPECT_EQ(table.RhoEnd(m, b, p), kRhoEnd);
}

// Every grid node with data is the line through the case's rows; past kRhoEnd there is none.
// The rows before first contact and those where rho falls are left out (their junk 1e6 would
// show).
TEST_F(WrenchTableTest, ResampledOntoTheGridLinearly) {
  const WrenchTable table(table_path_);
  for (int m = 0; m < 2; ++m) {
    for (int b = 0; b < 2; ++b) {
      for (int p = 0; p < 2; ++p) {
        for (size_t r = 0; r < table.rho().size(); ++r) {
          const double rho = table.rho()[r];
          const auto body = table.Sample(m, b, p, static_cast<int>(r), WrenchTable::Frame::kBody);
          const auto scoop = table.Sample(m, b, p, static_cast<int>(r));
          if (rho > kRhoEnd) {
            EXPECT_TRUE(std::isnan(scoop[0])) << rho;
            continue;
          }
          for (int q = 0; q < 6; ++q) {
            const double want_body = Wrench(m, table.bite_depths()[b], p + 1, q, rho);
            const double want_scoop = Wrench(m, table.bite_depths()[b], p + 1, 6 + q, rho);
            EXPECT_NEAR(body[q], want_body, 1e-12 * std::abs(want_body)) << m << b << p << r;
            EXPECT_NEAR(scoop[q], want_scoop, 1e-12 * std::abs(want_scoop)) << m << b << p << r;
          }
        }
      }
    }
  }
}

TEST_F(WrenchTableTest, QueryReproducesStoredSamplesExactly) {
  const WrenchTable table(table_path_);
  const double depths_mm[2] = {5, 10};
  for (int m = 0; m < 2; ++m) {
    for (int b = 0; b < 2; ++b) {
      for (int p = 0; p < 2; ++p) {
        for (int r = 0; r <= 200; r += 7) {
          const auto stored = table.Sample(m, b, p, r);
          const auto got = table.Query(table.materials()[m], depths_mm[b], p + 1, r);
          for (int q = 0; q < 6; ++q) EXPECT_EQ(got[q], stored[q]) << m << b << p << r << q;
          const auto body = table.Query(table.materials()[m], depths_mm[b], p + 1, r, false,
                                        WrenchTable::Frame::kBody);
          EXPECT_EQ(body[0], table.Sample(m, b, p, r, WrenchTable::Frame::kBody)[0]);
        }
      }
    }
  }
}

TEST_F(WrenchTableTest, QueryIsLinearInRhoAndBiteDepth) {
  const WrenchTable table(table_path_);
  // Between grid nodes: the blend of the two nodes.
  for (double f : {0.25, 0.5, 0.9}) {
    const auto a = table.Sample(0, 1, 1, 120);
    const auto c = table.Sample(0, 1, 1, 121);
    const auto got = table.Query("snow", 10, 2, 120 + f);
    for (int q = 0; q < 6; ++q)
      EXPECT_NEAR(got[q], (1 - f) * a[q] + f * c[q], 1e-14 * std::abs(a[q])) << f << q;
  }
  // Between bite depths (5 and 10 mm): the blend of the two at the same rho.
  for (double d : {6.0, 7.5, 9.0}) {
    const double s = (d - 5) / 5;
    const auto lo = table.Query("ice", 5, 1, 77.5);
    const auto hi = table.Query("ice", 10, 1, 77.5);
    const auto got = table.Query("ice", d, 1, 77.5);
    for (int q = 0; q < 6; ++q)
      EXPECT_NEAR(got[q], (1 - s) * lo[q] + s * hi[q], 1e-14 * std::abs(lo[q])) << d << q;
  }
  // The wrench of the cases is linear in bite depth too: the query gives its closed form.
  const auto got = table.Query("ice", 7.5, 2, 150);
  EXPECT_NEAR(got[0], Wrench(1, 0.0075, 2, 6, 0.15), 1e-12);
}

TEST_F(WrenchTableTest, OutOfDomainThrowsUnlessClamped) {
  const WrenchTable table(table_path_);
  EXPECT_THROW(table.Query("sand", 5, 1, 10), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 5, 3, 10), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 5, 0, 10), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 4.9, 1, 10), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 10.1, 1, 10), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 5, 1, -0.5), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 5, 1, 451), OutOfTableDomain);
  EXPECT_THROW(table.Query("snow", 5, 1, 200.5), OutOfTableDomain);  // past the pass's data
  EXPECT_THROW(table.Query("snow", 5, 1, NAN), OutOfTableDomain);
  EXPECT_NO_THROW(table.Query("snow", 5, 1, 200));
  // An InputError, so the CLI exits 2.
  EXPECT_THROW(table.Query("snow", 5, 1, 300), sim::InputError);
  try {
    table.Query("snow", 12, 1, 10);
    FAIL();
  } catch (const OutOfTableDomain& e) {
    EXPECT_NE(std::string(e.what()).find("bite depth 12 mm is outside the table's 5..10 mm"),
              std::string::npos)
        << e.what();
  }
  // Clamped: bite depth to its range, rho to the last node with data.
  EXPECT_EQ(table.Query("snow", 12, 1, 10, true), table.Query("snow", 10, 1, 10));
  EXPECT_EQ(table.Query("snow", 2, 1, 10, true), table.Query("snow", 5, 1, 10));
  EXPECT_EQ(table.Query("snow", 5, 1, 300, true), table.Query("snow", 5, 1, 200));
  EXPECT_EQ(table.Query("snow", 5, 1, -3, true), table.Query("snow", 5, 1, 0));
  EXPECT_THROW(table.Query("sand", 5, 1, 10, true), OutOfTableDomain);  // never clamped
}

TEST_F(WrenchTableTest, CsvHasTheLanderColumnsAndTheTableValues) {
  const WrenchTable table(table_path_);
  const std::string csv = (dir_ / "table.csv").string();
  table.ExportCsv(csv);
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz");
  int rows = 0;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) v.push_back(std::strtod(field.c_str(), nullptr));
    ASSERT_EQ(v.size(), 10u) << line;
    const int m = v[0] == 1 ? 0 : 1;
    const int b = v[1] == 0.005 ? 0 : 1;
    const int r = static_cast<int>(std::lround(v[3] * 1e3));
    EXPECT_EQ(v[3], table.rho()[r]);
    const auto stored = table.Sample(m, b, static_cast<int>(v[2]) - 1, r);
    for (int q = 0; q < 6; ++q) EXPECT_EQ(v[4 + q], stored[q]) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2 * 2 * 2 * 201);  // rho 0..200 mm in each cell
}

TEST_F(WrenchTableTest, TwoCasesOfOneCellAreRefused) {
  const fs::path dir = dir_ / "twice";
  WriteCase(dir, "a", "snow", 0.005);
  WriteCase(dir, "b", "snow", 0.005);
  EXPECT_THROW(sim::BuildWrenchTable(dir.string(), (dir / "t.h5").string()), sim::InputError);
  EXPECT_THROW(sim::BuildWrenchTable((dir_ / "none").string(), (dir / "t.h5").string()),
               sim::InputError);
}

// The CLI: build, query (exit 2 out of the domain), export-csv.
TEST_F(WrenchTableTest, CommandLine) {
  const std::string table = (dir_ / "cli_table.h5").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim("table build " + dir_.string() + " -o " + table +
                                       " --rho-step-mm 1"),
            0);
  const std::string out = (dir_ / "query.json").string();
  const std::string cmd = std::string(SCOOPSIM_BINARY) + " table query " + table +
                          " --material snow --bite-depth-mm 10 --pass 2 --rho-mm 120 > " + out;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::stringstream json;
  json << std::ifstream(out).rdbuf();
  const auto stored = WrenchTable(table).Sample(0, 1, 1, 120);
  char expected[64];
  std::snprintf(expected, sizeof expected, "\"F\":[%.17g,", stored[0]);
  EXPECT_NE(json.str().find(expected), std::string::npos) << json.str();
  EXPECT_EQ(scoopsim_test::RunScoopsim("table query " + table +
                                       " --material snow --bite-depth-mm 20 --pass 2 --rho-mm 1"),
            2);
  // Metres (as scenes and the CSV have them): the same line; mm and m of one quantity together,
  // or neither, are one line and exit 2.
  const std::string metres = (dir_ / "query_m.json").string();
  ASSERT_EQ(scoopsim_test::RunScoopsim(
                "table query " + table +
                " --material snow --bite-depth 0.010 --pass 2 --rho 0.120 >" + metres),
            0);
  std::stringstream json_m;
  json_m << std::ifstream(metres).rdbuf();
  EXPECT_EQ(json_m.str(), json.str());
  const std::string err = (dir_ / "query_both.txt").string();
  EXPECT_EQ(scoopsim_test::RunScoopsim("table query " + table +
                                           " --material snow --bite-depth 0.01 --bite-depth-mm 10 "
                                           "--pass 2 --rho 0.12",
                                       err),
            2);
  std::stringstream both;
  both << std::ifstream(err).rdbuf();
  EXPECT_EQ(both.str(),
            "scoopsim: --bite-depth and --bite-depth-mm: expected one of them (metres or "
            "millimetres), got both\n");
  EXPECT_EQ(scoopsim_test::RunScoopsim("table query " + table +
                                       " --material snow --bite-depth 0.01 --pass 2"),
            2);
  EXPECT_EQ(scoopsim_test::RunScoopsim("table export-csv " + table + " -o " +
                                       (dir_ / "cli.csv").string()),
            0);
  EXPECT_TRUE(fs::exists(dir_ / "cli.csv"));
}

// What rho measures, and the export's rows, on a hand-built case whose CoM goes down 10 mm
// (blade first: along-trench travel 0), then round a quarter circle of radius R = 45 mm (along
// R sin(phi), path R phi), then 100 mm straight along the trench; the wrench a + k path.
// Closed forms: built by default (rho = the CoM's path length, grid every 2 mm, as the lander's
// table) the table at node rho_k is a + k rho_k to 1e-12, and the CSV has exactly one row per
// 2 mm node up to the path's end, rho = 0.002 k; built with --rho along, the node at x holds
// the wrench where the CoM's along-trench travel was x: a + k path(x), path(x) = 10 mm +
// R asin(x / R) on the arc and 10 mm + R pi / 2 + (x - R) after it (to 1e-6 N: rows every
// 0.1 mm of path, linear between them).
TEST(WrenchTableRho, PathByDefaultEvery2mmAndAlongOnRequest) {
  const fs::path dir = scoopsim_test::ProcessTempDir("wrench_table_rho");
  constexpr double kR = 0.045, kDrop = 0.01, kLine = 0.1, kA = 0.3, kK = 2.0;
  const double arc = kR * M_PI / 2, path_end = kDrop + arc + kLine;
  const auto path_of_along = [&](double x) {
    return x <= kR ? kDrop + kR * std::asin(x / kR) : kDrop + arc + (x - kR);
  };
  {
    const std::string scene =
        "materials: materials.yaml\nbed: {material: snow, radius: 0.008, count: 10}\n"
        "dig: {bite_depth: 0.005, passes: 1}\n";
    sim::H5Output out((dir / "cases" / "snow_b5.h5").string(), scene, "test");
    double t = 0;
    const int n = static_cast<int>(std::lround(path_end / 1e-4));
    for (int i = 0; i <= n; ++i) {
      const double path = i * 1e-4, p = 1, contacts = 2;
      double along = 0;
      if (path > kDrop + arc) {
        along = kR + (path - kDrop - arc);
      } else if (path > kDrop) {
        along = kR * std::sin((path - kDrop) / kR);
      }
      out.AppendRow("/scoop/time", &t, 1);
      out.AppendRow("/scoop/pass", &p, 1);
      out.AppendRow("/scoop/rho", &along, 1);
      out.AppendRow("/scoop/rho_path", &path, 1);
      out.AppendRow("/scoop/contacts", &contacts, 1);
      const double w[3] = {kA + kK * path, 0, 0};
      for (const char* name :
           {"/scoop/force_body", "/scoop/torque_body", "/scoop/force_scoop", "/scoop/torque_scoop"})
        out.AppendRow(name, w, 3);
      t += 1e-3;
    }
    out.Close();
  }
  // Default: path, 2 mm.
  const std::string path_table = (dir / "path.h5").string();
  sim::BuildWrenchTable(dir.string(), path_table);
  const WrenchTable by_path(path_table);
  EXPECT_EQ(by_path.rho_definition(), sim::RhoDefinition::kPath);
  EXPECT_DOUBLE_EQ(by_path.rho_step(), 2e-3);
  ASSERT_EQ(by_path.rho().size(), 226u);
  for (size_t r = 0; r < by_path.rho().size(); ++r) {
    const double rho = by_path.rho()[r];
    const double got = by_path.Sample(0, 0, 0, static_cast<int>(r))[0];
    if (rho > by_path.RhoEnd(0, 0, 0)) {
      EXPECT_TRUE(std::isnan(got)) << rho;
    } else {
      EXPECT_NEAR(got, kA + kK * rho, 1e-12) << rho;
    }
  }
  const std::string csv = (dir / "path.csv").string();
  by_path.ExportCsv(csv);
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  int rows = 0;
  while (std::getline(in, line)) {
    double m, d, p, rho, fx;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &m, &d, &p, &rho, &fx), 5) << line;
    EXPECT_EQ(rho, rows * 2 / 1e3) << line;  // one row per 2 mm node, in order
    EXPECT_NEAR(fx, kA + kK * rho, 1e-12) << line;
    ++rows;
  }
  EXPECT_EQ(rows, static_cast<int>(std::floor(path_end / 2e-3 + 1e-9)) + 1);
  // On request: along the trench.
  sim::WrenchTableOptions options;
  options.rho = sim::RhoDefinition::kAlong;
  const std::string along_table = (dir / "along.h5").string();
  sim::BuildWrenchTable(dir.string(), along_table, options);
  const WrenchTable by_along(along_table);
  EXPECT_EQ(by_along.rho_definition(), sim::RhoDefinition::kAlong);
  EXPECT_NEAR(by_along.RhoEnd(0, 0, 0), kR + kLine, 1e-4);  // the last row, within a row
  for (size_t r = 1; r < by_along.rho().size(); ++r) {
    const double x = by_along.rho()[r];
    if (x > by_along.RhoEnd(0, 0, 0)) break;
    EXPECT_NEAR(by_along.Sample(0, 0, 0, static_cast<int>(r))[0], kA + kK * path_of_along(x), 1e-6)
        << x;
  }
}

// Defect: `table export-csv -o` (and `table build -o`) naming a FIFO or a device replaced it
// with a regular file and exited 0; a table file another process writes was replaced too. Each
// is refused, exit 2, one line naming the file; the node or the file is left as it was.
TEST_F(WrenchTableTest, OutputsThatCannotBeWrittenAreRefused) {
  const fs::path dir = dir_ / "special";
  fs::create_directories(dir);
  auto nodes = scoopsim_test::SpecialFiles(dir);
  ASSERT_FALSE(nodes.empty()) << "mkfifo failed";
  const std::string locked = (dir / "locked").string();
  std::ofstream(locked) << "another writer's";
  const int lock = scoopsim_test::HoldOutputLock(locked);
  ASSERT_GE(lock, 0);
  nodes.emplace_back(locked, "");
  for (const auto& [path, kind] : nodes) {
    for (const std::string& command : {"table export-csv " + table_path_ + " -o " + path,
                                       "table build " + dir_.string() + " -o " + path}) {
      SCOPED_TRACE(command);
      const std::string log = (dir / "refused.log").string();
      EXPECT_EQ(scoopsim_test::RunScoopsim(command, log), 2);
      const std::string expected =
          kind.empty()
              ? path +
                    ": another process (a scoopsim run?) is writing this file; give "
                    "this run another -o"
              : path + ": expected a regular file or a new path to write the output, got " + kind;
      EXPECT_EQ(scoopsim_test::ReadText(log), "scoopsim: " + expected + "\n");
    }
    EXPECT_EQ(fs::is_regular_file(path), kind.empty()) << path;
  }
  ::close(lock);
  EXPECT_EQ(scoopsim_test::ReadText(locked), "another writer's");
}

}  // namespace

// The cell of a case comes from its validated scene: the attributes a sweep writes from it, or,
// in a case file made before them, the stored text read as the scene loader reads it (its --set
// lines included; a raw parse of the text took the base scene's values). Closed form: the axes
// are exactly the values given.
TEST(WrenchTableCellTest, FromTheValidatedSceneNotTheRawText) {
  const fs::path dir = scoopsim_test::ProcessTempDir("wrench_table_cell");
  // An older case file: the text says snow at 10 mm, its overrides ice at 5 mm.
  WriteCase(dir, "old", "snow", 0.01,
            "# scoopsim --set bed.material=ice\n# scoopsim --set dig.bite_depth=0.005\n");
  // A sweep's case file: the attributes say snow at 20 mm (the text, snow at 10 mm, is not read).
  sim::Scene scene;
  scene.bed.material = "snow";
  scene.bed.radius_min = scene.bed.radius_max = 0.008;
  scene.dig.bite_depth = 0.02;
  WriteCase(dir, "new", "snow", 0.01, "", &scene);
  sim::BuildWrenchTable(dir.string(), (dir / "table.h5").string());
  const WrenchTable table((dir / "table.h5").string());
  EXPECT_EQ(table.materials(), (std::vector<std::string>{"snow", "ice"}));
  EXPECT_EQ(table.bite_depths(), (std::vector<double>{0.005, 0.02}));
}

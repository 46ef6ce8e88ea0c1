// The particle-size study's pure functions (sim/studies/size_study.cpp): the smoothing against its
// definition, a case's curve, eq. 6 and eq. 7 on synthetic curves with known answers, the cases
// (same solid volume, seeds, skin) and their sweep file, bad --sizes refused with one line.
#include "sim/studies/size_study.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/studies/sweep.h"
#include "tests/cli_util.h"

namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = SCOOPSIM_SOURCE_DIR;

fs::path TempDir() {
  static const fs::path dir = scoopsim_test::ProcessTempDir("size_study");
  return dir;
}

// ---- Smoothing

// S_i = mean{ y_j : |t_j - t_i| <= w/2 }, written out as the definition reads (every j, in order).
std::vector<double> MeanByDefinition(const std::vector<double>& t, const std::vector<double>& y,
                                     double window) {
  std::vector<double> s(t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    double sum = 0;
    int n = 0;
    for (size_t j = 0; j < t.size(); ++j) {
      if (std::abs(t[j] - t[i]) <= window / 2 + 1e-9) {
        sum += y[j];
        ++n;
      }
    }
    s[i] = sum / n;
  }
  return s;
}

// Uneven times and a rough signal: the sliding window equals the definition exactly (the same
// rows summed in the same order), for windows from none to wider than the series.
TEST(SizeStudySmoothingTest, EqualsItsDefinition) {
  std::vector<double> t, y;
  double time = 0;
  for (int k = 0; k < 300; ++k) {
    time += 1e-3 * (1 + (k * 7919) % 5);  // steps of 1-5 ms
    t.push_back(time);
    y.push_back(std::sin(0.37 * k) * 10 + (k % 11));
  }
  for (double window : {0.0, 0.001, 0.01, 0.05, 0.2, 10.0}) {
    SCOPED_TRACE(window);
    const std::vector<double> got = sim::CentredMovingMean(t, y, window);
    const std::vector<double> want = MeanByDefinition(t, y, window);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], want[i]) << i;
  }
}

// Closed form on rows every 1 ms of y = 3 + 200 t, window 10 ms (11 rows): a centred mean of a
// line is the line (interior rows, 1e-12); at the first row the window holds rows 0..5 only
// (one-sided), whose mean is y(2.5 ms) (1e-12); a zero window returns y itself.
TEST(SizeStudySmoothingTest, LineAndItsEnds) {
  std::vector<double> t, y;
  for (int k = 0; k < 100; ++k) {
    t.push_back(1e-3 * k);
    y.push_back(3 + 200 * t.back());
  }
  const std::vector<double> s = sim::CentredMovingMean(t, y, 0.01);
  for (int k = 5; k < 95; ++k) EXPECT_NEAR(s[k], y[k], 1e-12) << k;
  EXPECT_NEAR(s[0], 3 + 200 * 2.5e-3, 1e-12);
  EXPECT_NEAR(s[99], 3 + 200 * 96.5e-3, 1e-12);
  EXPECT_EQ(sim::CentredMovingMean(t, y, 0), y);
}

// ---- A case's curve

// Rows of pass 1 before contact (|F| = 0) are dropped, time starts at first contact, rows of pass
// 2 are left out; |F| and |T| are norms; the peaks are the smoothed maxima.
TEST(SizeStudyCurveTest, FromFirstContactOfPassOne) {
  sim::ScoopSeries s;
  for (int k = 0; k < 60; ++k) {
    s.time.push_back(1.0 + 1e-3 * k);
    s.pass.push_back(k < 50 ? 1 : 2);
    s.rho.push_back(k < 10 ? 0 : 1e-3 * (k - 10));
    const double f = k < 10 ? 0 : (k == 30 ? 40 : 4);  // one spike of 40 N among 4 N
    s.force_world.push_back({0, 0.6 * f, 0.8 * f});
    s.torque_world.push_back({0.5 * f, 0, 0});
    s.pose.push_back({});
  }
  const sim::SizeCurve c = sim::MakeSizeCurve(s, 0.004);  // 5 rows
  ASSERT_EQ(c.time.size(), 40u);                          // rows 10..49
  EXPECT_NEAR(c.time[0], 0, 1e-15);
  EXPECT_NEAR(c.time[39], 0.039, 1e-12);
  EXPECT_EQ(c.rho[0], 0);
  EXPECT_NEAR(c.force[20], 40, 1e-12);
  EXPECT_NEAR(c.torque[20], 20, 1e-12);
  // The spike averaged with four rows of 4 N: (40 + 16) / 5.
  EXPECT_NEAR(c.peak_force, 56.0 / 5, 1e-12);
  EXPECT_NEAR(c.peak_torque, 28.0 / 5, 1e-12);
}

// ---- Eq. 6 and eq. 7

// A synthetic dig: |F| a plateau of `force` N over 0.2 s, |T| = force x `lever`, on ramps; the
// plateau is wider than the window, so the smoothed peak is the plateau exactly.
sim::SizePeak SyntheticCase(double size_mm, int bed, double force, double lever) {
  sim::ScoopSeries s;
  for (int k = 0; k <= 400; ++k) {
    const double t = 1e-3 * k;
    const double shape = t < 0.1 ? t / 0.1 : (t <= 0.3 ? 1 : std::max(0.0, (0.4 - t) / 0.1));
    s.time.push_back(t);
    s.pass.push_back(1);
    s.rho.push_back(0.3 * t);
    s.force_world.push_back({force * shape + 1e-3, 0, 0});
    s.torque_world.push_back({0, 0, force * lever * shape});
  }
  const sim::SizeCurve c = sim::MakeSizeCurve(s, 0.05);
  return {size_mm, bed, c.peak_force, c.peak_torque, 60.0 * bed};
}

// One bed each. Eq. 6: MPE = (peak - peak_2mm) / peak_2mm x 100, signed; peaks 10 (2 mm),
// 11.5 (4 mm: +15%), 7 (6 mm: -30%), lever 0.1 m (torque's MPE the same). Tolerance 1e-9 %.
TEST(SizeStudyMpeTest, EquationSixOnSyntheticCurves) {
  const std::vector<sim::SizePeak> peaks = {
      SyntheticCase(6, 1, 7, 0.1), SyntheticCase(2, 1, 10, 0.1), SyntheticCase(4, 1, 11.5, 0.1)};
  EXPECT_NEAR(peaks[1].peak_force, 10 + 1e-3, 1e-12);
  const std::vector<sim::SizeRow> rows = sim::SummarizeSizes(peaks, 20);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].size_mm, 2);  // ascending; the finest is the reference
  EXPECT_EQ(rows[1].size_mm, 4);
  EXPECT_EQ(rows[2].size_mm, 6);
  EXPECT_EQ(rows[0].mpe_force_pct, 0);
  EXPECT_NEAR(rows[1].mpe_force_pct, 100 * (11.501 - 10.001) / 10.001, 1e-9);
  EXPECT_NEAR(rows[1].mpe_torque_pct, 15, 1e-9);
  EXPECT_NEAR(rows[2].mpe_torque_pct, -30, 1e-9);
  EXPECT_TRUE(rows[1].within);
  EXPECT_FALSE(rows[2].within);  // |-30| > 20: the tolerance is on |MPE|
  EXPECT_EQ(rows[1].cpu_s_mean, 60);
  EXPECT_EQ(sim::PercentError(12, 10), 20);
}

// Several beds: peak = the bed mean, MPE against the reference's bed mean, the spread each bed's
// peak against that mean. 2 mm beds 9 and 11 (mean 10; spread -10, +10 %); 4 mm beds 11 and 12
// (mean 11.5: +15 %; spread +10, +20 %). Tolerance 1e-12 %.
TEST(SizeStudyMpeTest, BedMeansAndSpread) {
  std::vector<sim::SizePeak> peaks = {
      {2, 1, 9, 0.9, 10}, {2, 2, 11, 1.1, 30}, {4, 1, 11, 1.0, 5}, {4, 2, 12, 1.3, 7}};
  const std::vector<sim::SizeRow> rows = sim::SummarizeSizes(peaks, 20);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].beds, 2);
  EXPECT_NEAR(rows[0].peak_force_mean, 10, 1e-12);
  EXPECT_NEAR(rows[0].mpe_force_min_pct, -10, 1e-12);
  EXPECT_NEAR(rows[0].mpe_force_max_pct, 10, 1e-12);
  EXPECT_EQ(rows[0].cpu_s_mean, 20);
  EXPECT_NEAR(rows[1].peak_force_mean, 11.5, 1e-12);
  EXPECT_EQ(rows[1].peak_force_min, 11);
  EXPECT_EQ(rows[1].peak_force_max, 12);
  EXPECT_NEAR(rows[1].mpe_force_pct, 15, 1e-12);
  EXPECT_NEAR(rows[1].mpe_force_min_pct, 10, 1e-12);
  EXPECT_NEAR(rows[1].mpe_force_max_pct, 20, 1e-12);
  EXPECT_NEAR(rows[1].mpe_torque_pct, 15, 1e-12);      // 1.15 against 1.0
  EXPECT_NEAR(rows[1].mpe_torque_max_pct, 30, 1e-12);  // 1.3: one bed outside
  EXPECT_TRUE(rows[1].within);
  EXPECT_FALSE(rows[1].within_spread);
}

// Rows of an earlier run join this run's (`--prior`): the 4 mm row of BedMeansAndSpread given as a
// row (beds 2, mean 11.5 [11, 12], torque 1.15 [1.0, 1.3]) beside the 2 mm peaks summarized here,
// scored against 2 mm's means (10, 1.0): the same hand-computed MPEs as there (+15 [+10, +20],
// torque +15 [0, +30]), whatever MPE the row carried in; rows come out by size. Tolerance 1e-12 %.
TEST(SizeStudyMpeTest, RowsOfAnEarlierRunScoreAsIfSummarizedTogether) {
  sim::SizeRow earlier;
  earlier.size_mm = 4;
  earlier.beds = 2;
  earlier.peak_force_mean = 11.5;
  earlier.peak_force_min = 11;
  earlier.peak_force_max = 12;
  earlier.peak_torque_mean = 1.15;
  earlier.peak_torque_min = 1.0;
  earlier.peak_torque_max = 1.3;
  earlier.mpe_force_pct = 99;  // against that run's reference: recomputed
  std::vector<sim::SizeRow> rows = {earlier};
  for (const sim::SizeRow& r : sim::SummarizeSizes({{2, 1, 9, 0.9, 10}, {2, 2, 11, 1.1, 30}}, 20))
    rows.push_back(r);
  rows = sim::ScoreSizes(rows, 20);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].size_mm, 2);
  EXPECT_NEAR(rows[0].mpe_force_min_pct, -10, 1e-12);
  EXPECT_NEAR(rows[1].mpe_force_pct, 15, 1e-12);
  EXPECT_NEAR(rows[1].mpe_force_min_pct, 10, 1e-12);
  EXPECT_NEAR(rows[1].mpe_force_max_pct, 20, 1e-12);
  EXPECT_NEAR(rows[1].mpe_torque_pct, 15, 1e-12);
  EXPECT_NEAR(rows[1].mpe_torque_min_pct, 0, 1e-12);
  EXPECT_NEAR(rows[1].mpe_torque_max_pct, 30, 1e-12);
  EXPECT_TRUE(rows[1].within);
  EXPECT_FALSE(rows[1].within_spread);
  // A size twice (here and in the earlier run) is refused.
  rows.push_back(earlier);
  EXPECT_THROW(sim::ScoreSizes(rows, 20), std::invalid_argument);
}

// An earlier run's size_study.csv read back (`--prior`): peaks, beds and cost from its rows; a
// file of another scene, another smoothing window, another header, a field that is not a number,
// peaks out of order, or no rows: an InputError naming the file, the line and the column.
TEST(SizeStudyMpeTest, EarlierRunsRowsAreReadAndBadFilesRefused) {
  const std::string scene = kSourceDir + "/scenes/paper/size_S10.yaml";
  const std::string head =
      "# scoopsim study particle-size scenes/paper/size_S10.yaml (scoopsim 0.1.0): paper\n"
      "# smoothing: centred moving mean over 0.05 s of time, S_i = ...\n"
      "# verdict: largest_within_20pct_mm=5.25\n";
  const std::string good_row =
      "5.25,2,1.13535366,1.10681807,1.16388925,16.6,13.7,19.6,0.0819815487,0.0810767026,"
      "0.0828863948,10.8,9.6,12.0,1,728.621";
  const auto write = [&](const std::string& name, const std::string& text) {
    const std::string path = (TempDir() / name).string();
    std::ofstream(path) << text;
    return path;
  };
  const std::vector<sim::SizeRow> rows = sim::ReadSizeRows(
      write("prior_good.csv", head + sim::SizeCsvHeader() + "\n" + good_row + "\n"), scene, 0.05);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].size_mm, 5.25);
  EXPECT_EQ(rows[0].beds, 2);
  EXPECT_EQ(rows[0].peak_force_mean, 1.13535366);
  EXPECT_EQ(rows[0].peak_force_max, 1.16388925);
  EXPECT_EQ(rows[0].peak_torque_min, 0.0810767026);
  EXPECT_EQ(rows[0].cpu_s_mean, 728.621);

  struct Bad {
    std::string name, text, key;
    int line;
    double smooth;
  };
  const std::string csv_head = head + sim::SizeCsvHeader() + "\n";
  const std::vector<Bad> bad = {
      {"other_scene", "# scoopsim study particle-size scenes/paper/size_S2.yaml (x)\n", "scene", 1,
       0.05},
      {"other_window", csv_head + good_row + "\n", "smoothing", 2, 0.1},
      {"header", head + "size_mm,beds\n" + good_row + "\n", "", 4, 0.05},
      {"word", csv_head + "5.25,2,x" + good_row.substr(good_row.find(',', 5)) + "\n",
       "peak_force_mean", 5, 0.05},
      {"order", csv_head + "5.25,2,1.2,1.1,1.16,0,0,0,0.08,0.081,0.083,0,0,0,1,7\n",
       "peak_force_mean", 5, 0.05},
      {"no_rows", csv_head, "", 4, 0.05},
      {"twice", csv_head + good_row + "\n" + good_row + "\n", "size_mm", 6, 0.05},
  };
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.name);
    const std::string path = write("prior_" + b.name + ".csv", b.text);
    try {
      sim::ReadSizeRows(path, scene, b.smooth);
      ADD_FAILURE() << "accepted";
    } catch (const sim::InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.key(), b.key) << e.what();
      EXPECT_EQ(e.line(), b.line) << e.what();
    }
  }
}

sim::SizeRow Row(double size, double mpe_force, double mpe_torque, bool spread_ok = true) {
  sim::SizeRow r;
  r.size_mm = size;
  r.mpe_force_pct = mpe_force;
  r.mpe_torque_pct = mpe_torque;
  r.within = std::abs(mpe_force) <= 20 && std::abs(mpe_torque) <= 20;
  r.within_spread = r.within && spread_ok;
  return r;
}

// Eq. 7: the largest d with every size from the reference up to d within 20 % for force and
// torque. 3 mm within, 4 mm out on torque alone (+25 %), 5 mm within by chance: 3 mm, not 5.
// With the spread: 3 mm's beds are not all within, so 2 mm (the reference always counts).
TEST(SizeStudyMpeTest, EquationSevenLargestConvergedSize) {
  const std::vector<sim::SizeRow> rows = {Row(2, 0, 0), Row(3, 12, -19.9, false), Row(4, 5, 25),
                                          Row(5, 3, 3)};
  EXPECT_EQ(sim::LargestWithin(rows, false), 3);
  EXPECT_EQ(sim::LargestWithin(rows, true), 2);
  // All within: the coarsest; exactly 20 % counts as within (<=).
  EXPECT_EQ(sim::LargestWithin({Row(2, 0, 0), Row(3, 20, -20), Row(8, -1, 1)}, false), 8);
  // Nothing above the reference within: the reference.
  EXPECT_EQ(sim::LargestWithin({Row(2, 0, 0), Row(3, -21, 0)}, false), 2);
}

// The 20% crossing: |MPE| linear in d between the last size within and the first beyond.
// Force: 4 mm at 16, 5 mm at 36 -> 4 + (20 - 16) / (36 - 16) x 1 = 4.2 mm. Torque: first
// beyond at 6 mm (29), the size before it 5 mm (-19: |MPE| 19) -> 5 + (20 - 19) / (29 - 19) x 1
// = 5.1 mm. Both: the smaller, 4.2 mm. (Relative 1e-12.)
TEST(SizeStudyMpeTest, ToleranceCrossingInterpolatesInDiameter) {
  const std::vector<sim::SizeRow> rows = {Row(2, 0, 0), Row(4, 16, -10), Row(5, 36, -19),
                                          Row(6, 50, 29)};
  const sim::ToleranceCrossing c = sim::CrossTolerance(rows, 20);
  EXPECT_NEAR(c.force_mm, 4.2, 4.2e-12);
  EXPECT_NEAR(c.torque_mm, 5.1, 5.1e-12);
  EXPECT_NEAR(c.mm, 4.2, 4.2e-12);
  // The crossing is never below eq. 7's verdict, and below the next size.
  EXPECT_GE(c.mm, sim::LargestWithin(rows, false));
  // Within at every size: none (NaN); one quantity within everywhere: the other's crossing.
  EXPECT_TRUE(std::isnan(sim::CrossTolerance({Row(2, 0, 0), Row(3, 20, -20)}, 20).mm));
  const sim::ToleranceCrossing t = sim::CrossTolerance({Row(2, 0, 0), Row(3, 10, 30)}, 20);
  EXPECT_TRUE(std::isnan(t.force_mm));
  EXPECT_NEAR(t.torque_mm, 2 + 20.0 / 30.0, 1e-12);
  EXPECT_EQ(t.mm, t.torque_mm);
}

TEST(SizeStudyMpeTest, ReferenceWithoutForceIsRefused) {
  EXPECT_THROW(sim::SummarizeSizes({{2, 1, 0, 1, 0}, {4, 1, 3, 1, 0}}, 20), std::invalid_argument);
  EXPECT_THROW(sim::SummarizeSizes({}, 20), std::invalid_argument);
}

// The CSV's columns, exactly as the report reads them.
TEST(SizeStudyMpeTest, CsvColumns) {
  EXPECT_EQ(sim::SizeCsvHeader(),
            "size_mm,beds,peak_force_mean,peak_force_min,peak_force_max,mpe_force_pct,"
            "mpe_force_min_pct,mpe_force_max_pct,peak_torque_mean,peak_torque_min,"
            "peak_torque_max,mpe_torque_pct,mpe_torque_min_pct,mpe_torque_max_pct,within_20,"
            "cpu_s_mean");
  sim::SizeRow r = Row(8.25, 12.5, -3);
  r.beds = 2;
  const std::string line = sim::SizeCsvLine(r);
  EXPECT_EQ(std::count(line.begin(), line.end(), ','), 15) << line;
  EXPECT_EQ(line.rfind("8.25,2,", 0), 0u) << line;
}

// ---- Cases

// size_S10.yaml (15369 spheres of 10 mm, skin 2.5 mm, seed 1) at 10, 5 and 2.5 mm, two beds: the
// count x (10/d)^3 (the same solid volume to rounding: relative 1e-6), skin x d/10, seeds 1 and 2,
// names d<mm>_b<bed>; the sweep file of these cases loads, and its scenes hold the values.
TEST(SizeStudyCasesTest, SameVolumeScaledSkinSeedsDiffer) {
  const sim::Scene base = sim::LoadScene(kSourceDir + "/scenes/paper/size_S10.yaml");
  const std::vector<sim::SizeCase> cases = sim::SizeCases(base, {10, 5, 2.5}, 2);
  ASSERT_EQ(cases.size(), 6u);
  const double d0 = 0.010;
  for (const sim::SizeCase& c : cases) {
    SCOPED_TRACE(c.name);
    const double d = c.size_mm / 1000;
    EXPECT_EQ(c.radius, d / 2);
    EXPECT_EQ(c.count, std::llround(15369 * std::pow(d0 / d, 3)));
    EXPECT_NEAR(c.count * d * d * d, 15369 * d0 * d0 * d0, 1e-6 * 15369 * d0 * d0 * d0);
    EXPECT_NEAR(c.skin, 0.0025 * d / d0, 1e-15);
    EXPECT_EQ(c.seed, static_cast<uint64_t>(c.bed));
  }
  EXPECT_EQ(cases[0].name, "d10_b1");
  EXPECT_EQ(cases[1].name, "d10_b2");
  EXPECT_EQ(cases[5].name, "d2.5_b2");
  EXPECT_EQ(cases[2].count, 15369 * 8);
  EXPECT_NE(cases[2].seed, cases[3].seed);

  const fs::path sweep_file = TempDir() / "size.sweep.yaml";
  std::ofstream(sweep_file) << sim::SizeSweepText(kSourceDir + "/scenes/paper/size_S10.yaml",
                                                  cases);
  const sim::Sweep sweep = sim::LoadSweep(sweep_file.string());
  ASSERT_EQ(sweep.cases.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    const sim::Scene& s = sweep.cases[k].scene;
    EXPECT_EQ(sweep.cases[k].name, cases[k].name);
    EXPECT_EQ(s.bed.radius_max, cases[k].radius);
    EXPECT_EQ(s.bed.count, cases[k].count);
    EXPECT_EQ(s.bed.seed, cases[k].seed);
    EXPECT_EQ(s.skin, cases[k].skin);
    EXPECT_EQ(s.bed.material, base.bed.material);
  }
}

// A scene whose skin is the default (a quarter diameter) gets no neighbor.skin: it scales alone.
TEST(SizeStudyCasesTest, DefaultSkinIsLeftToTheScene) {
  sim::Scene base = sim::LoadScene(kSourceDir + "/scenes/paper/size_S10.yaml");
  base.skin_given = false;
  const std::vector<sim::SizeCase> cases = sim::SizeCases(base, {10, 4}, 1);
  EXPECT_EQ(cases[1].skin, 0);
  EXPECT_EQ(sim::SizeSweepText("x.yaml", cases).find("neighbor.skin"), std::string::npos);
}

// Scenes the study cannot vary, and bad sizes or beds: InputError naming the key.
TEST(SizeStudyCasesTest, BadScenesAndSizesAreRefused) {
  const sim::Scene base = sim::LoadScene(kSourceDir + "/scenes/paper/size_S10.yaml");
  const auto key_of = [](auto make) {
    try {
      make();
    } catch (const sim::InputError& e) {
      return e.key();
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(key_of([&] { sim::SizeCases(base, {10}, 1); }), "--sizes");
  EXPECT_EQ(key_of([&] { sim::SizeCases(base, {10, 0}, 1); }), "--sizes");
  EXPECT_EQ(key_of([&] { sim::SizeCases(base, {10, NAN}, 1); }), "--sizes");
  EXPECT_EQ(key_of([&] { sim::SizeCases(base, {10, 4, 10}, 1); }), "--sizes");
  EXPECT_EQ(key_of([&] { sim::SizeCases(base, {10, 4}, 0); }), "--beds");
  const sim::Scene shape = sim::LoadScene(kSourceDir + "/scenes/paper/shape_study.yaml");
  EXPECT_EQ(key_of([&] { sim::SizeCases(shape, {10, 4}, 1); }), "bed.clump");
  const sim::Scene two_passes = sim::LoadScene(kSourceDir + "/scenes/sweeps/tiny_scene.yaml");
  EXPECT_EQ(key_of([&] { sim::SizeCases(two_passes, {10, 4}, 1); }), "dig.passes");
  const sim::Scene saved_bed = sim::LoadScene(kSourceDir + "/scenes/paper/lut_snow_b15.yaml");
  EXPECT_NE(key_of([&] { sim::SizeCases(saved_bed, {10, 4}, 1); }), "(no error)");
}

// A bad --sizes on the command line: one line naming the option and what was expected, exit 2,
// before any work (no output folder).
TEST(SizeStudyCasesTest, BadSizesOnTheCommandLineExitTwo) {
  const std::string scene = kSourceDir + "/scenes/paper/size_S10.yaml";
  for (const std::string sizes : {"10,-2", "10", "10,abc", "10,8,10"}) {
    SCOPED_TRACE(sizes);
    const fs::path out = TempDir() / "cli_bad";
    const std::string log = (TempDir() / "cli_bad.log").string();
    EXPECT_EQ(
        scoopsim_test::RunScoopsim(
            "study particle-size " + scene + " -o " + out.string() + " --sizes " + sizes, log),
        2);
    const std::string text = scoopsim_test::ReadText(log);
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
    EXPECT_NE(text.find("--sizes"), std::string::npos) << text;
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace

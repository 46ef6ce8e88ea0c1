// The particle-size study's pure functions (sim/studies/size_study.h): cases, smoothing, eq. 6 and 7.
#include "sim/studies/size_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace sim {
namespace {

// A number as short as it reads back exactly ("%.17g" would print 0.0050000000000000001).
std::string Shortest(double v) {
  char text[40];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

std::string SizeList(const std::vector<double>& sizes_mm) {
  std::string s;
  for (double d : sizes_mm) s += (s.empty() ? "" : ",") + Shortest(d);
  return s;
}

}  // namespace

std::vector<double> StudySizesMm() { return {2, 2.5, 3.25, 4, 5.25, 6.5, 8.25, 10}; }

std::vector<SizeCase> SizeCases(const Scene& base, const std::vector<double>& sizes_mm, int beds,
                                size_t min_sizes) {
  const std::string& file = base.path;
  const auto fail = [&](const std::string& key, const std::string& expected,
                        const std::string& got) {
    throw InputError(file, SceneLine(base, key), key, expected, got,
                     "study particle-size varies the diameter of a bed of spheres");
  };
  if (!base.bed.clump.empty()) fail("bed.clump", "no clumps (spheres only)", base.bed.clump);
  if (base.bed.radius_min != base.bed.radius_max)
    fail("bed.radius", "one radius (a number)", "a range");
  if (!base.bed.file.empty())
    fail("bed.file", "none: each case pours its own bed", "'" + base.bed.file + "'");
  if (!base.dig.enabled) fail("dig", "a dig (the study compares the scoop's wrench)", "none");
  if (base.dig.passes != 1)
    fail("dig.passes", "1 (the study compares one pass)", std::to_string(base.dig.passes));

  const std::string sizes_expected =
      min_sizes >= 2 ? "at least two different diameters in mm, each finite and > 0 (e.g. 10,8.25)"
                     : "different diameters in mm, each finite and > 0 (e.g. 10,8.25)";
  if (sizes_mm.size() < std::max<size_t>(min_sizes, 1)) {
    throw InputError("study particle-size", 0, "--sizes", sizes_expected,
                     "'" + SizeList(sizes_mm) + "'");
  }
  for (size_t k = 0; k < sizes_mm.size(); ++k) {
    const double d = sizes_mm[k];
    if (!std::isfinite(d) || !(d > 0)) {
      throw InputError("study particle-size", 0, "--sizes", sizes_expected, Shortest(d));
    }
    for (size_t j = 0; j < k; ++j) {
      if (sizes_mm[j] == d)
        throw InputError("study particle-size", 0, "--sizes", sizes_expected,
                         Shortest(d) + " twice");
    }
  }
  if (beds < 1 || beds > 1000) {
    throw InputError("study particle-size", 0, "--beds", "a number of beds in 1..1000",
                     std::to_string(beds));
  }

  const double d0 = 2 * base.bed.radius_max;  // [m]
  std::vector<SizeCase> cases;
  for (double d_mm : sizes_mm) {
    const double d = d_mm / 1000;
    const double scale = d0 / d;
    const double count = std::round(static_cast<double>(base.bed.count) * scale * scale * scale);
    if (!(count >= 1) || count > 1e12) {
      throw InputError("study particle-size", 0, "--sizes",
                       "diameters that give between 1 and 1e12 spheres of the scene's volume",
                       Shortest(d_mm));
    }
    for (int b = 1; b <= beds; ++b) {
      SizeCase c;
      c.size_mm = d_mm;
      c.bed = b;
      c.name = "d" + Shortest(d_mm) + "_b" + std::to_string(b);
      c.radius = d / 2;
      c.count = static_cast<int64_t>(count);
      c.seed = base.bed.seed + static_cast<uint64_t>(b - 1);
      c.skin = base.skin_given ? base.skin * d / d0 : 0;
      cases.push_back(c);
    }
  }
  return cases;
}

std::string SizeSweepText(const std::string& scene_path, const std::vector<SizeCase>& cases) {
  std::ostringstream out;
  out << "# The cases of `scoopsim study particle-size` (sim/studies/size_study.h): one per diameter and\n"
         "# bed, the scene's solid volume in each (count x (d0/d)^3), the neighbour skin scaled\n"
         "# with the diameter, bed.seed + bed - 1. Written by the study; `scoopsim sweep` runs\n"
         "# it too.\n"
      << "scene: " << scene_path << "\ncases:\n";
  for (const SizeCase& c : cases) {
    out << "  - {name: " << c.name << ", set: {bed.radius: " << Shortest(c.radius)
        << ", bed.count: " << c.count << ", bed.seed: " << c.seed;
    if (c.skin > 0) out << ", neighbor.skin: " << Shortest(c.skin);
    out << "}}\n";
  }
  return out.str();
}

std::vector<double> CentredMovingMean(const std::vector<double>& t, const std::vector<double>& y,
                                      double window) {
  if (t.size() != y.size()) throw std::invalid_argument("CentredMovingMean: t and y differ");
  const double half = window / 2 + 1e-9;
  const size_t n = y.size();
  std::vector<double> out(n);
  // A sliding window [lo, hi) over ascending t; the sum is taken afresh for each row (windows are
  // tens of rows) so that the result is exactly the mean of its window, in order.
  size_t lo = 0, hi = 0;
  for (size_t i = 0; i < n; ++i) {
    while (t[lo] < t[i] - half) ++lo;
    if (hi < i + 1) hi = i + 1;
    while (hi < n && t[hi] <= t[i] + half) ++hi;
    double sum = 0;
    for (size_t j = lo; j < hi; ++j) sum += y[j];
    out[i] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

SizeCurve MakeSizeCurve(const ScoopSeries& s, double window) {
  SizeCurve c;
  const size_t n = s.time.size();
  if (s.force_world.size() != n || s.torque_world.size() != n || s.rho.size() != n ||
      s.pass.size() != n)
    throw std::invalid_argument("MakeSizeCurve: the series differ in length");
  size_t first = n;
  for (size_t k = 0; k < n && first == n; ++k)
    if (s.pass[k] == 1 && dem::Norm(s.force_world[k]) > 0) first = k;
  for (size_t k = first; k < n; ++k) {
    if (s.pass[k] != 1) break;
    c.time.push_back(s.time[k] - s.time[first]);
    c.rho.push_back(s.rho[k]);
    c.force.push_back(dem::Norm(s.force_world[k]));
    c.torque.push_back(dem::Norm(s.torque_world[k]));
  }
  c.force_smooth = CentredMovingMean(c.time, c.force, window);
  c.torque_smooth = CentredMovingMean(c.time, c.torque, window);
  for (double f : c.force_smooth) c.peak_force = std::max(c.peak_force, f);
  for (double m : c.torque_smooth) c.peak_torque = std::max(c.peak_torque, m);
  return c;
}

double PercentError(double value, double reference) {
  return (value - reference) / reference * 100.0;
}

std::vector<SizeRow> SummarizeSizes(const std::vector<SizePeak>& peaks, double tolerance_pct) {
  if (peaks.empty()) throw std::invalid_argument("SummarizeSizes: no peaks");
  std::vector<double> sizes;
  for (const SizePeak& p : peaks) sizes.push_back(p.size_mm);
  std::sort(sizes.begin(), sizes.end());
  sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());

  // Per size: beds, mean / min / max of each peak, mean cost.
  std::vector<SizeRow> rows;
  for (double d : sizes) {
    SizeRow r;
    r.size_mm = d;
    r.peak_force_min = r.peak_torque_min = std::numeric_limits<double>::infinity();
    r.peak_force_max = r.peak_torque_max = -std::numeric_limits<double>::infinity();
    for (const SizePeak& p : peaks) {
      if (p.size_mm != d) continue;
      ++r.beds;
      r.peak_force_mean += p.peak_force;
      r.peak_torque_mean += p.peak_torque;
      r.cpu_s_mean += p.cpu_s;
      r.peak_force_min = std::min(r.peak_force_min, p.peak_force);
      r.peak_force_max = std::max(r.peak_force_max, p.peak_force);
      r.peak_torque_min = std::min(r.peak_torque_min, p.peak_torque);
      r.peak_torque_max = std::max(r.peak_torque_max, p.peak_torque);
    }
    r.peak_force_mean /= r.beds;
    r.peak_torque_mean /= r.beds;
    r.cpu_s_mean /= r.beds;
    rows.push_back(r);
  }
  return ScoreSizes(std::move(rows), tolerance_pct);
}

std::vector<SizeRow> ScoreSizes(std::vector<SizeRow> rows, double tolerance_pct) {
  if (rows.empty()) throw std::invalid_argument("ScoreSizes: no rows");
  std::sort(rows.begin(), rows.end(),
            [](const SizeRow& a, const SizeRow& b) { return a.size_mm < b.size_mm; });
  for (size_t k = 1; k < rows.size(); ++k) {
    if (rows[k].size_mm == rows[k - 1].size_mm)
      throw std::invalid_argument("ScoreSizes: the size " + Shortest(rows[k].size_mm) +
                                  " mm twice");
  }
  // Eq. 6 against the finest size's bed means.
  const double ref_force = rows.front().peak_force_mean;
  const double ref_torque = rows.front().peak_torque_mean;
  if (!(ref_force > 0) || !(ref_torque > 0))
    throw std::invalid_argument("SummarizeSizes: the finest size's peaks are not > 0");
  for (size_t k = 0; k < rows.size(); ++k) {
    SizeRow& r = rows[k];
    r.mpe_force_pct = PercentError(r.peak_force_mean, ref_force);
    r.mpe_force_min_pct = PercentError(r.peak_force_min, ref_force);
    r.mpe_force_max_pct = PercentError(r.peak_force_max, ref_force);
    r.mpe_torque_pct = PercentError(r.peak_torque_mean, ref_torque);
    r.mpe_torque_min_pct = PercentError(r.peak_torque_min, ref_torque);
    r.mpe_torque_max_pct = PercentError(r.peak_torque_max, ref_torque);
    const auto in = [&](double pct) { return std::abs(pct) <= tolerance_pct; };
    r.within = in(r.mpe_force_pct) && in(r.mpe_torque_pct);
    r.within_spread = k == 0 || (in(r.mpe_force_min_pct) && in(r.mpe_force_max_pct) &&
                                 in(r.mpe_torque_min_pct) && in(r.mpe_torque_max_pct));
  }
  return rows;
}

std::vector<SizeRow> ReadSizeRows(const std::string& path, const std::string& scene_path,
                                  double smooth_s) {
  std::ifstream in(path);
  if (!in)
    throw InputError(path, 0, "", "a size_study.csv of `scoopsim study particle-size`",
                     "no such file (or it cannot be read)");
  const std::string scene_name = std::filesystem::path(scene_path).filename().string();
  const std::string first_key = "# scoopsim study particle-size ";
  const std::string smooth_key = "# smoothing: centred moving mean over ";
  std::vector<SizeRow> rows;
  std::vector<int> row_lines;  // the line of each row
  std::string text;
  int line = 0;
  bool header = false, smoothing = false;
  std::vector<std::string> columns;  // SizeCsvHeader()'s names, for the messages
  {
    std::stringstream names(SizeCsvHeader());
    for (std::string name; std::getline(names, name, ',');) columns.push_back(name);
  }
  const auto fail = [&](const std::string& key, const std::string& expected,
                        const std::string& got) {
    throw InputError(path, line, key, expected, got);
  };
  while (std::getline(in, text)) {
    ++line;
    if (line == 1) {
      // "# scoopsim study particle-size SCENE (scoopsim VERSION): ..."
      if (text.rfind(first_key, 0) != 0)
        fail("", "a first line '" + first_key + "SCENE (...'", "'" + text.substr(0, 60) + "'");
      const std::string rest = text.substr(first_key.size());
      const std::string scene = rest.substr(0, rest.find(' '));
      if (std::filesystem::path(scene).filename().string() != scene_name)
        fail("scene", "the same scene as this study's (" + scene_name + ")", "'" + scene + "'");
      continue;
    }
    if (text.rfind(smooth_key, 0) == 0) {
      const double w = std::strtod(text.c_str() + smooth_key.size(), nullptr);
      if (std::abs(w - smooth_s) > 1e-12 * std::max(1.0, smooth_s))
        fail("smoothing", "the same window as this study's --smooth-s " + Shortest(smooth_s) + " s",
             Shortest(w) + " s");
      smoothing = true;
      continue;
    }
    if (text.empty() || text[0] == '#') continue;
    if (!header) {
      if (text != SizeCsvHeader()) fail("", "the header line '" + SizeCsvHeader() + "'", text);
      header = true;
      continue;
    }
    std::vector<double> v;
    std::stringstream fields(text);
    std::string field;
    while (std::getline(fields, field, ',')) {
      const size_t k = v.size();
      char* end = nullptr;
      const double x = std::strtod(field.c_str(), &end);
      if (k >= columns.size())
        fail("", std::to_string(columns.size()) + " columns", std::to_string(k + 1) + " or more");
      if (field.empty() || *end != '\0' || !std::isfinite(x))
        fail(columns[k], "a finite number", "'" + field + "'");
      v.push_back(x);
    }
    if (v.size() != columns.size())
      fail("", std::to_string(columns.size()) + " columns", std::to_string(v.size()));
    SizeRow r;
    r.size_mm = v[0];
    if (!(r.size_mm > 0)) fail("size_mm", "a diameter > 0 [mm]", Shortest(r.size_mm));
    for (size_t k = 0; k < rows.size(); ++k) {
      if (rows[k].size_mm == r.size_mm)
        fail("size_mm", "each size once (line " + std::to_string(row_lines[k]) + " has it)",
             Shortest(r.size_mm));
    }
    if (!(v[1] >= 1) || v[1] != std::floor(v[1]) || v[1] > 1000)
      fail("beds", "a number of beds in 1..1000", Shortest(v[1]));
    r.beds = static_cast<int>(v[1]);
    r.peak_force_mean = v[2];
    r.peak_force_min = v[3];
    r.peak_force_max = v[4];
    r.peak_torque_mean = v[8];
    r.peak_torque_min = v[9];
    r.peak_torque_max = v[10];
    r.cpu_s_mean = v[15];
    const auto ordered = [&](int col, double lo, double mean, double hi) {
      const double slack = 1e-9 * std::abs(mean);
      if (!(lo > 0) || !(lo <= mean + slack) || !(mean <= hi + slack))
        fail(columns[col], "peaks with 0 < min <= mean <= max",
             Shortest(lo) + ", " + Shortest(mean) + ", " + Shortest(hi));
    };
    ordered(2, r.peak_force_min, r.peak_force_mean, r.peak_force_max);
    ordered(8, r.peak_torque_min, r.peak_torque_mean, r.peak_torque_max);
    rows.push_back(r);
    row_lines.push_back(line);
  }
  if (line == 0) fail("", "a size_study.csv of `scoopsim study particle-size`", "an empty file");
  if (!smoothing) fail("smoothing", "a line '" + smooth_key + "W s...'", "none");
  if (rows.empty()) fail("", "at least one row after the header line", "none");
  return rows;
}

double LargestWithin(const std::vector<SizeRow>& rows, bool spread) {
  double largest = rows.empty() ? 0 : rows.front().size_mm;
  for (size_t k = 1; k < rows.size(); ++k) {
    if (!(spread ? rows[k].within_spread : rows[k].within)) break;
    largest = rows[k].size_mm;
  }
  return largest;
}

ToleranceCrossing CrossTolerance(const std::vector<SizeRow>& rows, double tolerance_pct) {
  const auto cross = [&](double SizeRow::*mpe) {
    for (size_t k = 1; k < rows.size(); ++k) {
      const double a = std::abs(rows[k - 1].*mpe), b = std::abs(rows[k].*mpe);
      if (!(b > tolerance_pct)) continue;
      const double d0 = rows[k - 1].size_mm, d1 = rows[k].size_mm;
      return d0 + (tolerance_pct - a) / (b - a) * (d1 - d0);  // a <= tol < b
    }
    return std::numeric_limits<double>::quiet_NaN();
  };
  ToleranceCrossing c;
  c.force_mm = cross(&SizeRow::mpe_force_pct);
  c.torque_mm = cross(&SizeRow::mpe_torque_pct);
  c.mm = std::isnan(c.force_mm)    ? c.torque_mm
         : std::isnan(c.torque_mm) ? c.force_mm
                                   : std::min(c.force_mm, c.torque_mm);
  return c;
}

std::string SizeCsvHeader() {
  return "size_mm,beds,peak_force_mean,peak_force_min,peak_force_max,mpe_force_pct,"
         "mpe_force_min_pct,mpe_force_max_pct,peak_torque_mean,peak_torque_min,peak_torque_max,"
         "mpe_torque_pct,mpe_torque_min_pct,mpe_torque_max_pct,within_20,cpu_s_mean";
}

std::string SizeCsvLine(const SizeRow& r) {
  char line[512];
  std::snprintf(line, sizeof line,
                "%s,%d,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%d,%.6g",
                Shortest(r.size_mm).c_str(), r.beds, r.peak_force_mean, r.peak_force_min,
                r.peak_force_max, r.mpe_force_pct, r.mpe_force_min_pct, r.mpe_force_max_pct,
                r.peak_torque_mean, r.peak_torque_min, r.peak_torque_max, r.mpe_torque_pct,
                r.mpe_torque_min_pct, r.mpe_torque_max_pct, r.within ? 1 : 0, r.cpu_s_mean);
  return line;
}

}  // namespace sim

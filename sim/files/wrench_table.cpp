// The wrench lookup table (sim/files/wrench_table.h): built from a sweep's case files, read back,
// queried, exported as the lander simulator's CSV.
#include "sim/files/wrench_table.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>

#include "sim/files/h5_output.h"
#include "sim/files/internal_h5.h"

namespace sim {
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kSnapMm = 1e-9;  // a query this close to a stored value [mm] is that value

// The four wrench series of the table, in the order of a table row's 12 values.
const char* const kSeries[4] = {"force_body", "torque_body", "force_scoop", "torque_scoop"};

std::string Mm(double metres) {
  char s[32];
  std::snprintf(s, sizeof s, "%g mm", 1e3 * metres);
  return s;
}

// Shortest decimal text that reads back to the same double.
std::string Shortest(double v) {
  char s[64];
  const auto r = std::to_chars(s, s + sizeof s, v);
  return std::string(s, r.ptr);
}

// "spheres r 8 mm", "spheres r 4 mm to 8 mm", "clumps tetra4": the table's particle_size.
std::string ParticleSize(const std::string& clump, double radius_min, double radius_max) {
  if (!clump.empty()) return "clumps " + clump;
  if (radius_min != radius_max) return "spheres r " + Mm(radius_min) + " to " + Mm(radius_max);
  return "spheres r " + Mm(radius_max);
}

// The root attributes of a case's output that say which cell it fills (WriteTableCell).
constexpr const char* kCellMaterial = "table_material";
constexpr const char* kCellBiteDepth = "table_bite_depth";
constexpr const char* kCellParticleSize = "table_particle_size";

// What a case says about its table cell: the attributes WriteTableCell wrote from its validated
// scene, or, in a case file made before them, its stored scene text (sim::ParseStoredDig).
TableCell ReadTableCell(const h5::Reader& r, const std::string& file, const std::string& text) {
  TableCell cell;
  if (r.HasAttribute("/", kCellMaterial)) {
    cell.material = r.ReadStringAttribute("/", kCellMaterial);
    cell.bite_depth = r.ReadDoubleAttribute("/", kCellBiteDepth);
    cell.particle_size = r.ReadStringAttribute("/", kCellParticleSize);
    return cell;
  }
  const StoredDig stored = ParseStoredDig(text, file + ":scene_yaml");
  cell.material = stored.material;
  cell.bite_depth = stored.bite_depth;
  cell.particle_size = ParticleSize(stored.clump, stored.radius_min, stored.radius_max);
  return cell;
}

// One case's rows, the 12 wrench components of a row side by side.
struct CaseRows {
  std::string file, name, scene_yaml;
  TableCell cell;
  std::vector<double> pass, rho, contacts;
  std::vector<std::array<double, 12>> wrench;
};

CaseRows ReadCase(const fs::path& path, RhoDefinition rho) {
  CaseRows c;
  c.file = path.string();
  c.name = path.stem().string();
  const h5::Handle file = h5::OpenForReading(c.file, true);
  const h5::Reader r(c.file, file.get());
  c.scene_yaml = r.ReadStringAttribute("/", "scene_yaml");
  c.cell = ReadTableCell(r, c.file, c.scene_yaml);
  if (!r.Exists("/scoop/time")) r.Fail("/scoop/time", "missing: not the output of a dig");
  int64_t n = 0;
  r.Read<double>("/scoop/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1, &n);
  c.pass = r.ReadSeries<double>("/scoop/pass", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  const char* rho_name = rho == RhoDefinition::kPath ? "/scoop/rho_path" : "/scoop/rho";
  if (!r.Exists(rho_name)) {
    r.Fail(rho_name,
           "missing (a run made before 2026-12-06 records only /scoop/rho: run the "
           "case again, or build with --rho along)");
  }
  c.rho = r.ReadSeries<double>(rho_name, H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  c.contacts = r.ReadSeries<double>("/scoop/contacts", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  c.wrench.resize(static_cast<size_t>(n));
  for (int s = 0; s < 4; ++s) {
    const std::vector<dem::Vec3> v =
        r.ReadVectors(std::string("/scoop/") + kSeries[s], n, /*series=*/true);
    for (int64_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) c.wrench[i][3 * s + k] = v[i][k];
  }
  return c;
}

// The rule of wrench_table.h: the rows of pass `pass` from first contact, rho as its running
// maximum, linear between rows onto grid `rho`. *rows_used and *rho_end describe what was used.
std::vector<std::array<double, 12>> Resample(const CaseRows& c, int pass,
                                             const std::vector<double>& rho, int* rows_used,
                                             double* rho_end) {
  std::array<double, 12> nan_row;
  nan_row.fill(kNaN);
  std::vector<std::array<double, 12>> out(rho.size(), nan_row);
  std::vector<size_t> keep;  // rows where rho reaches a new maximum
  bool touched = false;
  for (size_t i = 0; i < c.pass.size(); ++i) {
    if (c.pass[i] != pass) continue;
    touched = touched || c.contacts[i] > 0;
    if (!touched) continue;
    if (keep.empty() || c.rho[i] > c.rho[keep.back()]) keep.push_back(i);
  }
  *rows_used = static_cast<int>(keep.size());
  *rho_end = keep.empty() ? kNaN : c.rho[keep.back()];
  if (keep.empty()) return out;
  size_t j = 0;
  for (size_t k = 0; k < rho.size(); ++k) {
    const double r = rho[k];
    if (r > c.rho[keep.back()]) break;
    if (r <= c.rho[keep.front()]) {
      out[k] = c.wrench[keep.front()];
      continue;
    }
    while (c.rho[keep[j + 1]] < r) ++j;  // rho[keep[j]] < r <= rho[keep[j + 1]]
    const double r0 = c.rho[keep[j]], r1 = c.rho[keep[j + 1]];
    const double t = (r - r0) / (r1 - r0);
    for (int q = 0; q < 12; ++q)
      out[k][q] = (1 - t) * c.wrench[keep[j]][q] + t * c.wrench[keep[j + 1]][q];
  }
  return out;
}

// ---- HDF5 writing of N-d arrays and string lists

void WriteNd(hid_t file, const std::string& name, hid_t file_type, hid_t memory_type,
             const std::vector<hsize_t>& dims, const void* data) {
  h5::Handle lcpl(h5::CheckId(H5Pcreate(H5P_LINK_CREATE), "H5Pcreate"), H5Pclose);
  h5::CheckOk(H5Pset_create_intermediate_group(lcpl.get(), 1), "H5Pset_create_intermediate_group");
  h5::Handle space(
      h5::CheckId(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                  "H5Screate_simple " + name),
      H5Sclose);
  h5::Handle d(h5::CheckId(H5Dcreate2(file, name.c_str(), file_type, space.get(), lcpl.get(),
                                      H5P_DEFAULT, H5P_DEFAULT),
                           "H5Dcreate2 " + name),
               H5Dclose);
  hsize_t total = 1;
  for (hsize_t n : dims) total *= n;
  if (total > 0)
    h5::CheckOk(H5Dwrite(d.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
                "H5Dwrite " + name);
}

void WriteStrings(hid_t file, const std::string& name, const std::vector<std::string>& values) {
  h5::Handle type(h5::CheckId(H5Tcopy(H5T_C_S1), "H5Tcopy"), H5Tclose);
  h5::CheckOk(H5Tset_size(type.get(), H5T_VARIABLE), "H5Tset_size");
  h5::CheckOk(H5Tset_cset(type.get(), H5T_CSET_UTF8), "H5Tset_cset");
  std::vector<const char*> pointers;
  for (const std::string& v : values) pointers.push_back(v.c_str());
  WriteNd(file, name, type.get(), type.get(), {values.size()}, pointers.data());
}

// A float dataset of exactly `dims`, read whole.
std::vector<double> ReadNd(const h5::Reader& r, const std::string& name,
                           const std::vector<hsize_t>& dims) {
  if (!r.Exists(name)) r.Fail(name, "missing");
  const h5::Handle d(H5Dopen2(r.file(), name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.valid()) r.Fail(name, "not a dataset");
  const h5::Handle space(H5Dget_space(d.get()), H5Sclose);
  std::vector<hsize_t> got(8);
  const int rank = H5Sget_simple_extent_dims(space.get(), got.data(), nullptr);
  got.resize(std::max(rank, 0));
  if (got != dims) {
    std::string want, have;
    for (hsize_t n : dims) want += (want.empty() ? "" : ", ") + std::to_string(n);
    for (hsize_t n : got) have += (have.empty() ? "" : ", ") + std::to_string(n);
    r.Fail(name, "expected shape (" + want + "), got (" + have + ")");
  }
  hsize_t total = 1;
  for (hsize_t n : dims) total *= n;
  std::vector<double> values(total);
  if (total > 0 &&
      H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
    r.Fail(name, "cannot be read");
  return values;
}

}  // namespace

TableCell TableCellOf(const Scene& scene) {
  return {scene.bed.material, scene.dig.bite_depth,
          ParticleSize(scene.bed.clump, scene.bed.radius_min, scene.bed.radius_max)};
}

void WriteTableCell(const Scene& scene, H5Output* out) {
  const TableCell cell = TableCellOf(scene);
  out->SetAttribute(kCellMaterial, cell.material);
  out->SetAttribute(kCellBiteDepth, cell.bite_depth);
  out->SetAttribute(kCellParticleSize, cell.particle_size);
}

const char* RhoDefinitionName(RhoDefinition d) {
  return d == RhoDefinition::kPath ? "path" : "along";
}

int LanderMaterialId(const std::string& name) {
  if (name == "snow") return 1;
  if (name == "ice") return 2;
  if (name == "sand") return 3;
  return 0;
}

std::string BuildWrenchTable(const std::string& dir, const std::string& table_path,
                             const WrenchTableOptions& options) {
  if (!(options.rho_step_mm > 0) || !(options.rho_max_mm >= 0))
    throw InputError("table build: expected a rho step > 0 and a rho end >= 0 (mm)");
  // Grid points: far past any pass's length is a typo, not a table.
  const double points = options.rho_max_mm / options.rho_step_mm + 1;
  if (!(points <= 1e7)) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "--rho-max-mm %g / --rho-step-mm %g: expected at most 1e7 grid points, got %.3g",
                  options.rho_max_mm, options.rho_step_mm, points);
    throw InputError(text);
  }
  // The table lands neither on a folder nor among the case files (the next build would read it
  // as one).
  std::error_code ec;
  if (fs::is_directory(table_path, ec))
    throw InputError("-o " + table_path + ": expected a file to write, got a folder");
  if (fs::weakly_canonical(fs::path(table_path).parent_path(), ec) ==
      fs::weakly_canonical(fs::path(dir) / "cases", ec)) {
    throw InputError("-o " + table_path + ": names a file in " + dir +
                     "/cases/, where the case files are; give another table file");
  }
  CheckOutputPath(table_path);
  // The cases, by file name.
  const fs::path cases_dir = fs::path(dir) / "cases";
  std::vector<fs::path> files;
  if (fs::is_directory(cases_dir)) {
    for (const auto& entry : fs::directory_iterator(cases_dir))
      if (entry.is_regular_file() && entry.path().extension() == ".h5")
        files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty())
    throw InputError(cases_dir.string() +
                     ": expected the case files of a sweep (<name>.h5), found none");
  std::vector<CaseRows> cases;
  for (const fs::path& f : files) cases.push_back(ReadCase(f, options.rho));

  // The axes: materials by lander id (then name), bite depths ascending, passes 1..P.
  std::vector<std::string> materials;
  std::set<double> depth_set;
  int max_pass = 0;
  for (const CaseRows& c : cases) {
    if (std::find(materials.begin(), materials.end(), c.cell.material) == materials.end())
      materials.push_back(c.cell.material);
    depth_set.insert(c.cell.bite_depth);
    for (double p : c.pass) max_pass = std::max(max_pass, static_cast<int>(p));
  }
  std::sort(materials.begin(), materials.end(), [](const std::string& a, const std::string& b) {
    const int ia = LanderMaterialId(a), ib = LanderMaterialId(b);
    if ((ia == 0) != (ib == 0)) return ia != 0;
    return ia != ib ? ia < ib : a < b;
  });
  std::vector<int> ids;
  int next_id = 10;
  for (const std::string& m : materials)
    ids.push_back(LanderMaterialId(m) != 0 ? LanderMaterialId(m) : next_id++);
  const std::vector<double> depths(depth_set.begin(), depth_set.end());
  std::vector<int> passes;
  for (int p = 1; p <= max_pass; ++p) passes.push_back(p);
  // The rho grid's points, counted in double first: past an int they overflowed the cast.
  constexpr double kMaxRhoPoints = 1e7;
  const double rho_points = std::floor(options.rho_max_mm / options.rho_step_mm + 1e-9) + 1;
  if (!(rho_points <= kMaxRhoPoints)) {
    char got[64];
    std::snprintf(got, sizeof got, "%.3g", rho_points);
    throw InputError(
        "--rho-max-mm / --rho-step-mm: expected a rho grid of at most 1e+07 points, "
        "got " +
        std::string(got));
  }
  const int n_rho = static_cast<int>(rho_points);
  std::vector<double> rho(n_rho);
  for (int k = 0; k < n_rho; ++k) rho[k] = k * options.rho_step_mm / 1e3;

  const size_t M = materials.size(), B = depths.size(), P = passes.size(), R = rho.size();
  std::vector<std::vector<double>> series(4, std::vector<double>(M * B * P * R * 3, kNaN));
  std::vector<double> rho_end(M * B * P, kNaN);
  std::vector<int32_t> rows(M * B * P, 0);
  std::vector<std::string> cell_case(M * B);
  std::vector<std::string> particle_size(M);
  for (const CaseRows& c : cases) {
    const size_t m =
        std::find(materials.begin(), materials.end(), c.cell.material) - materials.begin();
    const size_t b = std::find(depths.begin(), depths.end(), c.cell.bite_depth) - depths.begin();
    if (!cell_case[m * B + b].empty()) {
      throw InputError(c.file + ": a second case of material " + c.cell.material +
                       " and bite depth " + Mm(c.cell.bite_depth) + " (the first is " +
                       cell_case[m * B + b] + "); a table holds one");
    }
    cell_case[m * B + b] = c.name;
    if (particle_size[m].empty()) particle_size[m] = c.cell.particle_size;
    for (size_t p = 0; p < P; ++p) {
      const size_t cell = (m * B + b) * P + p;
      const auto values = Resample(c, passes[p], rho, &rows[cell], &rho_end[cell]);
      for (size_t k = 0; k < R; ++k)
        for (int s = 0; s < 4; ++s)
          for (int q = 0; q < 3; ++q) series[s][(cell * R + k) * 3 + q] = values[k][3 * s + q];
    }
  }

  // The file, written beside and renamed into place.
  const std::string tmp = table_path + ".tmp";
  try {
    h5::Handle file = h5::CreateFile(tmp, /*swmr=*/false, nullptr, table_path);
    const hid_t f = file.get();
    h5::WriteNewFile(f, table_path, [&] {
      std::string sizes, id_text;
      for (size_t m = 0; m < M; ++m) {
        sizes += (m ? "\n" : "") + materials[m] + ": " + particle_size[m];
        id_text += (m ? ", " : "") + materials[m] + "=" + std::to_string(ids[m]);
      }
      h5::WriteStringAttribute(f, "kind", "scoopsim wrench table");
      h5::WriteStringAttribute(f, "version", SCOOPSIM_VERSION);
      h5::WriteDoubleAttribute(f, "rho_step", options.rho_step_mm / 1e3);
      h5::WriteDoubleAttribute(f, "rho_max", rho.back());
      h5::WriteStringAttribute(f, "units", "SI: force N, torque N m, bite_depth m, rho m");
      h5::WriteStringAttribute(f, "rho_definition", RhoDefinitionName(options.rho));
      h5::WriteStringAttribute(
          f, "frames",
          "about the scoop's centre of mass; *_body: the study's body frame (X along the rotation "
          "axis, Z up, Y = Z x X forward along the trench); *_scoop: the l_scoop frame (the "
          "lander simulator's)");
      h5::WriteStringAttribute(
          f, "resample",
          "per pass: the rows from first contact, rho taken as its running maximum (a row enters "
          "where it raises it), linear in rho between rows onto rho_k = k * rho_step; below the "
          "first row its value; NaN past the pass's last row (cells/rho_end)");
      h5::WriteStringAttribute(f, "particle_size", sizes);
      h5::WriteStringAttribute(f, "material_ids", id_text);
      WriteStrings(f, "/materials/name", materials);
      WriteNd(f, "/materials/id", H5T_STD_I32LE, H5T_NATIVE_INT, {M}, ids.data());
      WriteStrings(f, "/materials/particle_size", particle_size);
      WriteNd(f, "/bite_depth", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {B}, depths.data());
      WriteNd(f, "/pass", H5T_STD_I32LE, H5T_NATIVE_INT, {P}, passes.data());
      WriteNd(f, "/rho", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {R}, rho.data());
      for (int s = 0; s < 4; ++s) {
        WriteNd(f, std::string("/scoop/") + kSeries[s], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                {M, B, P, R, 3}, series[s].data());
      }
      WriteNd(f, "/cells/rho_end", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {M, B, P}, rho_end.data());
      WriteNd(f, "/cells/rows", H5T_STD_I32LE, H5T_NATIVE_INT, {M, B, P}, rows.data());
      std::vector<std::string> names, paths, texts;
      for (const CaseRows& c : cases) {
        names.push_back(c.name);
        paths.push_back((fs::path("cases") / fs::path(c.file).filename()).string());
        texts.push_back(c.scene_yaml);
      }
      // (M x B) strings as a flat list of M * B: the case of each cell, "" for none.
      WriteStrings(f, "/cells/case", cell_case);
      WriteStrings(f, "/cases/name", names);
      WriteStrings(f, "/cases/file", paths);
      WriteStrings(f, "/cases/scene_yaml", texts);
    });
    if (file.reset() < 0) throw std::runtime_error("HDF5: closing " + tmp + " failed");
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);  // no stray temporary file
    throw;
  }
  PlaceOutput(tmp, table_path);  // under the output lock (sim/files/h5_output.h)
  char summary[256];
  std::snprintf(summary, sizeof summary,
                "%zu cases: %zu material(s), %zu bite depth(s), %zu pass(es), %zu rho nodes "
                "(step %g mm)",
                cases.size(), M, B, P, R, options.rho_step_mm);
  return summary;
}

// ---------------------------------------------------------------------------------------------
// Reading and querying

WrenchTable::WrenchTable(const std::string& path) : path_(path) {
  const h5::Handle file = h5::OpenForReading(path, false);
  const h5::Reader r(path, file.get());
  if (!r.HasAttribute("/", "kind") || r.ReadStringAttribute("/", "kind") != "scoopsim wrench table")
    r.Fail("/", "not a wrench table (attribute kind)");
  materials_ = r.ReadStrings("/materials/name");
  const size_t M = materials_.size();
  material_ids_ = r.Read<int>("/materials/id", H5T_INTEGER, H5T_NATIVE_INT, M, 1);
  bite_depths_ = r.Read<double>("/bite_depth", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1);
  passes_ = r.Read<int>("/pass", H5T_INTEGER, H5T_NATIVE_INT, -1, 1);
  rho_ = r.Read<double>("/rho", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1);
  rho_step_ = r.ReadDoubleAttribute("/", "rho_step");
  if (r.HasAttribute("/", "rho_definition")) {
    const std::string d = r.ReadStringAttribute("/", "rho_definition");
    if (d != "path" && d != "along")
      r.Fail("attribute rho_definition", "expected path or along, got " + d);
    rho_definition_ = d == "path" ? RhoDefinition::kPath : RhoDefinition::kAlong;
  }
  const hsize_t B = bite_depths_.size(), P = passes_.size(), R = rho_.size();
  if (M == 0 || B == 0 || P == 0 || R == 0) r.Fail("/", "an empty table");
  force_body_ = ReadNd(r, "/scoop/force_body", {M, B, P, R, 3});
  torque_body_ = ReadNd(r, "/scoop/torque_body", {M, B, P, R, 3});
  force_scoop_ = ReadNd(r, "/scoop/force_scoop", {M, B, P, R, 3});
  torque_scoop_ = ReadNd(r, "/scoop/torque_scoop", {M, B, P, R, 3});
  rho_end_ = ReadNd(r, "/cells/rho_end", {M, B, P});
}

size_t WrenchTable::Cell(int m, int b, int p) const {
  return (static_cast<size_t>(m) * bite_depths_.size() + b) * passes_.size() + p;
}

double WrenchTable::RhoEnd(int m, int b, int p) const { return rho_end_[Cell(m, b, p)]; }

std::array<double, 6> WrenchTable::Sample(int m, int b, int p, int r, Frame frame) const {
  const std::vector<double>& f = frame == Frame::kScoop ? force_scoop_ : force_body_;
  const std::vector<double>& t = frame == Frame::kScoop ? torque_scoop_ : torque_body_;
  const size_t at = (Cell(m, b, p) * rho_.size() + r) * 3;
  return {f[at], f[at + 1], f[at + 2], t[at], t[at + 1], t[at + 2]};
}

std::array<double, 6> WrenchTable::AtRho(int m, int b, int p, double rho_mm, bool clamp,
                                         Frame frame, const std::string& what) const {
  const double step_mm = rho_step_ * 1e3;
  const int last = static_cast<int>(rho_.size()) - 1;
  double position = rho_mm / step_mm;
  if (std::abs(position - std::round(position)) * step_mm <= kSnapMm)
    position = std::round(position);
  if (position < 0 || position > last) {
    if (!clamp) {
      throw OutOfTableDomain(path_ + ": rho " + Shortest(rho_mm) +
                             " mm is outside the table's 0.." + Shortest(last * step_mm) + " mm (" +
                             what + ")");
    }
    position = std::clamp(position, 0.0, static_cast<double>(last));
  }
  int i = static_cast<int>(std::floor(position));
  double t = position - i;
  if (i == last) t = 0;
  // Past the pass's data: the last node with data, when clamping.
  const auto has = [&](int k) { return !std::isnan(Sample(m, b, p, k, frame)[0]); };
  if (!has(i) || (t > 0 && !has(i + 1))) {
    const double end = rho_end_[Cell(m, b, p)];
    if (!clamp || std::isnan(end) || !has(0)) {
      throw OutOfTableDomain(
          path_ + ": rho " + Shortest(rho_mm) + " mm is past the end of the data of " + what +
          (std::isnan(end) ? " (no contact in that pass)"
                           : " (which ends at rho " + Shortest(end * 1e3) + " mm)") +
          "; ask for clamping to hold its last value");
    }
    while (!has(i)) --i;
    t = 0;
  }
  const std::array<double, 6> a = Sample(m, b, p, i, frame);
  if (t == 0) return a;
  const std::array<double, 6> c = Sample(m, b, p, i + 1, frame);
  std::array<double, 6> v;
  for (int q = 0; q < 6; ++q) v[q] = (1 - t) * a[q] + t * c[q];
  return v;
}

std::array<double, 6> WrenchTable::Query(const std::string& material, double bite_depth_mm,
                                         int pass, double rho_mm, bool clamp, Frame frame) const {
  const auto m = std::find(materials_.begin(), materials_.end(), material) - materials_.begin();
  if (m == static_cast<long>(materials_.size())) {
    std::string known;
    for (const std::string& name : materials_) known += (known.empty() ? "" : ", ") + name;
    throw OutOfTableDomain(path_ + ": material '" + material + "' is not in the table (" + known +
                           ")");
  }
  const auto p = std::find(passes_.begin(), passes_.end(), pass) - passes_.begin();
  if (p == static_cast<long>(passes_.size())) {
    throw OutOfTableDomain(path_ + ": pass " + std::to_string(pass) + " is not in the table (1.." +
                           std::to_string(passes_.back()) + ")");
  }
  if (!std::isfinite(bite_depth_mm) || !std::isfinite(rho_mm))
    throw OutOfTableDomain(path_ + ": bite depth and rho must be finite numbers");
  // The bite depth: a stored one, or between two.
  std::vector<double> depths_mm;
  for (double d : bite_depths_) depths_mm.push_back(d * 1e3);
  double d = bite_depth_mm;
  if (d < depths_mm.front() - kSnapMm || d > depths_mm.back() + kSnapMm) {
    if (!clamp) {
      throw OutOfTableDomain(path_ + ": bite depth " + Shortest(d) + " mm is outside the table's " +
                             Shortest(depths_mm.front()) + ".." + Shortest(depths_mm.back()) +
                             " mm");
    }
    d = std::clamp(d, depths_mm.front(), depths_mm.back());
  }
  int b = 0;
  double s = 0;
  for (size_t k = 0; k < depths_mm.size(); ++k) {
    if (std::abs(d - depths_mm[k]) <= kSnapMm) {
      b = static_cast<int>(k);
      s = 0;
      break;
    }
    if (k + 1 < depths_mm.size() && depths_mm[k] < d && d < depths_mm[k + 1]) {
      b = static_cast<int>(k);
      s = (d - depths_mm[k]) / (depths_mm[k + 1] - depths_mm[k]);
      break;
    }
  }
  const auto cell_name = [&](int bb) {
    return material + ", bite depth " + Shortest(depths_mm[bb]) + " mm, pass " +
           std::to_string(pass);
  };
  const std::array<double, 6> a =
      AtRho(static_cast<int>(m), b, static_cast<int>(p), rho_mm, clamp, frame, cell_name(b));
  if (s == 0) return a;
  const std::array<double, 6> c = AtRho(static_cast<int>(m), b + 1, static_cast<int>(p), rho_mm,
                                        clamp, frame, cell_name(b + 1));
  std::array<double, 6> v;
  for (int q = 0; q < 6; ++q) v[q] = (1 - s) * a[q] + s * c[q];
  return v;
}

void WrenchTable::ExportCsv(const std::string& csv_path, int digits) const {
  if (digits < 0 || digits > 17)
    throw InputError("--digits: expected 1 to 17 significant digits, got " +
                     std::to_string(digits));
  auto text = [digits](double v) {
    if (digits == 0) return Shortest(v);
    char s[64];
    std::snprintf(s, sizeof s, "%.*g", digits, v);
    return std::string(s);
  };
  if (fs::path(csv_path).has_parent_path())
    fs::create_directories(fs::path(csv_path).parent_path());
  CheckOutputPath(csv_path);
  const std::string tmp = csv_path + ".tmp";
  {
    errno = 0;
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw InputError(csv_path + ": cannot create the CSV file");
    out << "m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz\n";
    for (size_t m = 0; m < materials_.size(); ++m) {
      for (size_t b = 0; b < bite_depths_.size(); ++b) {
        for (size_t p = 0; p < passes_.size(); ++p) {
          for (size_t r = 0; r < rho_.size(); ++r) {
            const std::array<double, 6> w = Sample(m, b, p, r);
            if (std::isnan(w[0])) continue;
            out << material_ids_[m] << ',' << Shortest(bite_depths_[b]) << ',' << passes_[p] << ','
                << Shortest(rho_[r]);
            for (double v : w) out << ',' << text(v);
            out << '\n';
          }
        }
      }
    }
    out.flush();
    if (!out) {
      const int error = errno != 0 ? errno : EIO;
      std::error_code ignored;
      fs::remove(tmp, ignored);  // no stray temporary file
      throw OutputError(csv_path + ": write failed (" + std::strerror(error) + ")");
    }
  }
  PlaceOutput(tmp, csv_path);  // under the output lock (sim/files/h5_output.h)
}

}  // namespace sim

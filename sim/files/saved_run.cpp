#include "sim/files/saved_run.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "sim/files/internal_h5.h"

namespace sim {

int SampleAt(const std::vector<double>& time, double t) {
  const auto it = std::upper_bound(time.begin(), time.end(), t + 1e-9);
  return static_cast<int>(it - time.begin()) - 1;
}

int ScoopSeries::SampleAt(double t) const { return sim::SampleAt(time, t); }

struct SavedRun::Impl {
  h5::Handle file;
  h5::Reader in;
  std::vector<SnapshotInfo> snapshots;  // read on opening (the names are cheap)

  explicit Impl(const std::string& path)
      : file(h5::OpenForReading(path, true)), in(path, file.get()) {}
};

namespace {

// The names of every link under the group `group`, relative to it ("id", "meshes/scoop"); with
// `ok`, *ok = false instead of failing when they cannot all be read.
std::set<std::string> LinksUnder(const h5::Reader& in, const std::string& group,
                                 bool* ok = nullptr) {
  std::set<std::string> names;
  const auto add = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::set<std::string>*>(data)->insert(name);
    return 0;
  };
  herr_t status = -1;
  H5E_BEGIN_TRY {
    status = H5Lvisit_by_name(in.file(), group.c_str(), H5_INDEX_NAME, H5_ITER_INC, add, &names,
                              H5P_DEFAULT);
  }
  H5E_END_TRY;
  if (ok != nullptr) *ok = status >= 0;
  if (status < 0 && ok == nullptr) in.Fail(group, "cannot be read (damaged file?)");
  return names;
}

// Whether the last snapshot `group` was written whole: a run killed while writing a snapshot
// (written in one go and flushed after it, H5Output::WriteSnapshot) leaves it without its time
// or short of datasets, or with a link to an object never written. Whole: its time and every
// link the snapshot before it has (`previous`; for the first, the particle arrays up to `awake`,
// the last one written), all readable.
bool WrittenWhole(const h5::Reader& in, const std::string& group, const std::string& previous) {
  if (!in.HasAttribute(group, "time")) return false;
  bool readable = false;
  const std::set<std::string> have = LinksUnder(in, group, &readable);
  if (!readable) return false;  // a link to an object the kill kept off the disk
  const std::set<std::string> need =
      previous.empty() ? std::set<std::string>{"id", "position", "radius", "material", "awake"}
                       : LinksUnder(in, previous);
  return std::includes(have.begin(), have.end(), need.begin(), need.end());
}

}  // namespace

SavedRun::SavedRun(const std::string& h5_path) : impl_(std::make_unique<Impl>(h5_path)) {
  const h5::Reader& in = impl_->in;
  if (!in.Exists("/snapshots")) return;
  const std::vector<std::string> names = in.List("/snapshots");
  for (size_t k = 0; k < names.size(); ++k) {
    SnapshotInfo info;
    info.group = "/snapshots/" + names[k];
    // The last one may be the snapshot a kill cut short: left out unless whole.
    if (k + 1 == names.size() &&
        !WrittenWhole(in, info.group, k > 0 ? "/snapshots/" + names[k - 1] : ""))
      break;
    info.time = in.ReadDoubleAttribute(info.group, "time");
    impl_->snapshots.push_back(info);
  }
}

SavedRun::~SavedRun() = default;

const std::string& SavedRun::path() const { return impl_->in.path(); }

std::string SavedRun::RootAttribute(const std::string& name) const {
  if (!impl_->in.HasAttribute("/", name)) return "";
  return impl_->in.ReadStringAttribute("/", name);
}

std::string SavedRun::SceneYaml() const { return RootAttribute("scene_yaml"); }

StoredScene SavedRun::Scene() const {
  return ParseStoredScene(SceneYaml(), path() + ":scene_yaml");
}

std::vector<SnapshotInfo> SavedRun::Snapshots() const {
  if (!impl_->in.Exists("/snapshots")) {
    throw InputError(path() + ": no /snapshots group (run with output.snapshot_every > 0)");
  }
  if (impl_->snapshots.empty()) throw InputError(path() + ": /snapshots holds no snapshot");
  return impl_->snapshots;
}

void SavedRun::ReadSnapshot(const SnapshotInfo& snapshot, dem::Particles* particles) const {
  const h5::Reader& in = impl_->in;
  const std::string& base = snapshot.group;
  int64_t n = 0;
  dem::Particles p;
  p.id = in.Read<int64_t>(base + "/id", H5T_INTEGER, H5T_NATIVE_INT64, -1, 1, &n);
  p.x = in.ReadVectors(base + "/position", n);
  p.v = in.ReadVectors(base + "/velocity", n);
  p.w = in.ReadVectors(base + "/angular_velocity", n);
  p.radius = in.Read<double>(base + "/radius", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  p.material = in.Read<int32_t>(base + "/material", H5T_INTEGER, H5T_NATIVE_INT32, n, 1);
  *particles = std::move(p);
}

ScoopSeries SavedRun::Scoop() const {
  const h5::Reader& in = impl_->in;
  ScoopSeries s;
  if (!in.Exists("/scoop/time")) return s;
  int64_t n = 0;
  s.time = in.Read<double>("/scoop/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1, &n);
  // The other series hold at least /scoop/time's rows (H5Output writes a row of each per
  // sample, and time last in a flush: a killed or live file can hold more of the others).
  const auto column = [&](const char* name, hsize_t width) {
    return in.Exists(name) ? in.ReadSeries<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, n, width)
                           : std::vector<double>();
  };
  for (double pass : column("/scoop/pass", 1))
    s.pass.push_back(static_cast<int>(std::lround(pass)));
  s.rho = column("/scoop/rho", 1);
  if (in.Exists("/scoop/force_world"))
    s.force_world = in.ReadVectors("/scoop/force_world", n, /*series=*/true);
  if (in.Exists("/scoop/torque_world"))
    s.torque_world = in.ReadVectors("/scoop/torque_world", n, /*series=*/true);
  const std::vector<double> pose = column("/scoop/pose", 7);
  for (size_t k = 0; k + 7 <= pose.size(); k += 7) {
    const double* q = &pose[k];
    s.pose.push_back({{q[0], q[1], q[2]}, {q[3], q[4], q[5], q[6]}});
  }
  return s;
}

ArmSeries SavedRun::Arm() const {
  const h5::Reader& in = impl_->in;
  ArmSeries a;
  if (!in.Exists("/arm/time") || !in.HasAttribute("/", "arm_joints")) return a;
  std::string names = in.ReadStringAttribute("/", "arm_joints");
  for (size_t start = 0; start <= names.size();) {
    const size_t comma = std::min(names.find(',', start), names.size());
    if (comma > start) a.joints.push_back(names.substr(start, comma - start));
    start = comma + 1;
  }
  const hsize_t n = a.joints.size();
  if (n == 0) return a;
  int64_t rows = 0;
  a.time = in.Read<double>("/arm/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1, &rows);
  a.torque_demanded =
      in.ReadSeries<double>("/arm/torque_demanded", H5T_FLOAT, H5T_NATIVE_DOUBLE, rows, n);
  a.effort_limit =
      in.ReadSeries<double>("/arm/effort_limit", H5T_FLOAT, H5T_NATIVE_DOUBLE, rows, n);
  if (in.Exists("/arm/effort_derate")) {
    const std::vector<double> derate =
        in.ReadSeries<double>("/arm/effort_derate", H5T_FLOAT, H5T_NATIVE_DOUBLE, rows, n);
    for (size_t k = 0; k < a.effort_limit.size(); ++k) a.effort_limit[k] *= derate[k];
  }
  // uint64 since issue 40; float64 in older files (HDF5 converts either).
  a.fault_latched =
      in.ReadSeries<uint64_t>("/arm/fault_latched", H5T_NO_CLASS, H5T_NATIVE_UINT64, rows, 1);
  return a;
}

BondSeries SavedRun::Bonds() const {
  const h5::Reader& in = impl_->in;
  BondSeries s;
  if (in.Exists("/bonds/time")) {
    int64_t n = 0;
    s.time = in.Read<double>("/bonds/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1, &n);
    s.intact = in.ReadSeries<double>("/bonds/intact", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  }
  if (!in.Exists("/bonds/broken/time")) return s;
  int64_t m = 0;
  s.broken_time = in.Read<double>("/bonds/broken/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 1, &m);
  const std::vector<uint64_t> pair =
      in.ReadSeries<uint64_t>("/bonds/broken/pair", H5T_INTEGER, H5T_NATIVE_UINT64, m, 2);
  for (int64_t k = 0; k < m; ++k) {
    s.broken_a.push_back(static_cast<int64_t>(pair[2 * k]));
    s.broken_b.push_back(static_cast<int64_t>(pair[2 * k + 1]));
  }
  s.broken_position = in.ReadVectors("/bonds/broken/position", m, /*series=*/true);
  for (uint64_t mode :
       in.ReadSeries<uint64_t>("/bonds/broken/mode", H5T_INTEGER, H5T_NATIVE_UINT64, m, 1))
    s.broken_mode.push_back(static_cast<int>(mode));
  s.broken_stress =
      in.ReadSeries<double>("/bonds/broken/stress", H5T_FLOAT, H5T_NATIVE_DOUBLE, m, 1);
  return s;
}

std::vector<float> BrokenBondCounts(const std::vector<int64_t>& ids, const std::vector<int64_t>& a,
                                    const std::vector<int64_t>& b) {
  std::vector<float> counts(ids.size(), 0.0f);
  std::vector<std::pair<int64_t, size_t>> index(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) index[i] = {ids[i], i};
  std::sort(index.begin(), index.end());
  const auto add = [&](int64_t id) {
    const auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(id, size_t{0}));
    if (it != index.end() && it->first == id) counts[it->second] += 1.0f;
  };
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    add(a[k]);
    add(b[k]);
  }
  return counts;
}

std::vector<SnapshotMesh> SavedRun::ReadSnapshotMeshes(const SnapshotInfo& snapshot) const {
  const h5::Reader& in = impl_->in;
  std::vector<SnapshotMesh> meshes;
  const std::string group = snapshot.group + "/meshes";
  if (!in.Exists(group)) return meshes;
  for (const std::string& name : in.List(group)) {
    const std::string base = group + "/" + name;
    SnapshotMesh m;
    m.name = name;
    int64_t v = 0, t = 0;
    m.mesh.vertices = in.ReadVectors(base + "/points", -1);
    v = static_cast<int64_t>(m.mesh.vertices.size());
    const std::vector<int64_t> tri =
        in.Read<int64_t>(base + "/triangles", H5T_INTEGER, H5T_NATIVE_INT64, -1, 3, &t);
    for (int64_t k = 0; k < t; ++k) {
      std::array<int32_t, 3> c{};
      for (int j = 0; j < 3; ++j) {
        const int64_t index = tri[3 * k + j];
        if (index < 0 || index >= v) in.Fail(base + "/triangles", "index out of range");
        c[j] = static_cast<int32_t>(index);
      }
      m.mesh.triangles.push_back(c);
    }
    meshes.push_back(std::move(m));
  }
  return meshes;
}

double SavedRun::RootNumber(const std::string& name, double fallback) const {
  if (!impl_->in.HasAttribute("/", name)) return fallback;
  return impl_->in.ReadDoubleAttribute("/", name);
}

}  // namespace sim

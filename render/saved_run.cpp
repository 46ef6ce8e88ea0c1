#include "render/saved_run.h"

#include <hdf5.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sim/mesh_io.h"

namespace render {
namespace {

// Closes an HDF5 identifier when it goes out of scope.
struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
};

bool Exists(hid_t file, const std::string& path) {
  // Walk the path one link at a time: H5Lexists fails on a missing intermediate group.
  size_t pos = 0;
  while ((pos = path.find('/', pos + 1)) != std::string::npos) {
    if (H5Lexists(file, path.substr(0, pos).c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0;
}

// Reads a whole dataset as `type` (native) into a flat vector; *rows gets the first dimension.
template <typename T>
std::vector<T> Read(const std::string& file_name, hid_t file, const std::string& path, hid_t type,
                    size_t* rows = nullptr) {
  const Id set{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  if (set.id < 0) throw sim::InputError(file_name + ": " + path + ": cannot open dataset");
  const Id space{H5Dget_space(set.id), H5Sclose};
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_dims(space.id, dims, nullptr);
  if (rank < 1 || rank > 2)
    throw sim::InputError(file_name + ": " + path + ": expected 1 or 2 dimensions");
  std::vector<T> data(static_cast<size_t>(dims[0] * (rank == 2 ? dims[1] : 1)));
  if (!data.empty() && H5Dread(set.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0) {
    throw sim::InputError(file_name + ": " + path + ": cannot read dataset");
  }
  if (rows != nullptr) *rows = static_cast<size_t>(dims[0]);
  return data;
}

// A root or group string attribute ("" when absent or not a string).
std::string StringAttribute(hid_t object, const char* name) {
  if (H5Aexists(object, name) <= 0) return "";
  const Id attr{H5Aopen(object, name, H5P_DEFAULT), H5Aclose};
  const Id type{H5Aget_type(attr.id), H5Tclose};
  if (H5Tget_class(type.id) != H5T_STRING) return "";
  // Read with a copy of the file's own type: a converted character set (sim writes UTF-8) would
  // make HDF5 refuse the read.
  const Id mem{H5Tcopy(type.id), H5Tclose};
  if (H5Tis_variable_str(type.id) > 0) {
    char* value = nullptr;
    if (H5Aread(attr.id, mem.id, &value) < 0 || value == nullptr) return "";
    std::string out(value);
    H5free_memory(value);
    return out;
  }
  std::vector<char> buffer(H5Tget_size(type.id) + 1, '\0');
  if (H5Aread(attr.id, mem.id, buffer.data()) < 0) return "";
  return std::string(buffer.data());
}

double DoubleAttribute(hid_t object, const char* name, double fallback) {
  if (H5Aexists(object, name) <= 0) return fallback;
  const Id attr{H5Aopen(object, name, H5P_DEFAULT), H5Aclose};
  double v = fallback;
  if (H5Aread(attr.id, H5T_NATIVE_DOUBLE, &v) < 0) return fallback;
  return v;
}

// box.min / box.max of the stored scene; false when the text has none.
bool SceneBox(const std::string& yaml, dem::Vec3* lo, dem::Vec3* hi) {
  try {
    const YAML::Node box = YAML::Load(yaml)["box"];
    if (!box || !box["min"] || !box["max"]) return false;
    for (int i = 0; i < 3; ++i) {
      const double a = box["min"][i].as<double>(), b = box["max"][i].as<double>();
      (i == 0 ? lo->x : i == 1 ? lo->y : lo->z) = a;
      (i == 0 ? hi->x : i == 1 ? hi->y : hi->z) = b;
    }
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

// Opens a run's file read-only, the SWMR way when it is still open for writing (a run in
// progress, or one that was killed).
hid_t OpenRun(const std::string& h5_path) {
  hid_t file_id = H5I_INVALID_HID;
  H5E_BEGIN_TRY {
    file_id = H5Fopen(h5_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file_id < 0) {
      file_id = H5Fopen(h5_path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT);
    }
  }
  H5E_END_TRY;
  if (file_id < 0) throw sim::InputError(h5_path + ": not a readable HDF5 file");
  return file_id;
}

}  // namespace

std::string ReadSceneYaml(const std::string& h5_path) {
  const Id file{OpenRun(h5_path), H5Fclose};
  const Id root{H5Gopen2(file.id, "/", H5P_DEFAULT), H5Gclose};
  return StringAttribute(root.id, "scene_yaml");
}

int RenderSavedRun(const std::string& h5_path, FrameSequence* frames, bool quiet) {
  if (frames->options().settings.color_by == ColorField::kForce) {
    throw sim::InputError(h5_path +
                          ": cannot colour by force: snapshots store no forces (use "
                          "speed, depth or material, or render while running with --frames)");
  }
  const Id file{OpenRun(h5_path), H5Fclose};
  // Missing optional objects are probed, not errors: keep HDF5 from printing its error stack
  // while this file is read (restored on the way out).
  struct QuietErrors {
    H5E_auto2_t handler = nullptr;
    void* data = nullptr;
    QuietErrors() {
      H5Eget_auto2(H5E_DEFAULT, &handler, &data);
      H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    }
    ~QuietErrors() { H5Eset_auto2(H5E_DEFAULT, handler, data); }
  } quiet_errors;

  if (!Exists(file.id, "/snapshots")) {
    throw sim::InputError(h5_path + ": no /snapshots group (run with output.snapshot_every > 0)");
  }
  const Id group{H5Gopen2(file.id, "/snapshots", H5P_DEFAULT), H5Gclose};
  H5G_info_t info{};
  H5Gget_info(group.id, &info);
  std::vector<std::string> names;
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256] = {};
    if (H5Lget_name_by_idx(group.id, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof(name),
                           H5P_DEFAULT) > 0) {
      names.emplace_back(name);
    }
  }
  std::sort(names.begin(), names.end());
  if (names.empty()) throw sim::InputError(h5_path + ": /snapshots holds no snapshot");

  const Id root{H5Gopen2(file.id, "/", H5P_DEFAULT), H5Gclose};
  dem::Vec3 box_lo, box_hi;
  const bool has_box = SceneBox(StringAttribute(root.id, "scene_yaml"), &box_lo, &box_hi);

  // The scoop's series for the caption, when the run had a dig.
  std::vector<double> scoop_time, scoop_pass, scoop_rho, scoop_force, scoop_pose;
  if (Exists(file.id, "/scoop/time")) {
    scoop_time = Read<double>(h5_path, file.id, "/scoop/time", H5T_NATIVE_DOUBLE);
    if (Exists(file.id, "/scoop/pass"))
      scoop_pass = Read<double>(h5_path, file.id, "/scoop/pass", H5T_NATIVE_DOUBLE);
    if (Exists(file.id, "/scoop/rho"))
      scoop_rho = Read<double>(h5_path, file.id, "/scoop/rho", H5T_NATIVE_DOUBLE);
    if (Exists(file.id, "/scoop/force_world"))
      scoop_force = Read<double>(h5_path, file.id, "/scoop/force_world", H5T_NATIVE_DOUBLE);
    if (Exists(file.id, "/scoop/pose"))
      scoop_pose = Read<double>(h5_path, file.id, "/scoop/pose", H5T_NATIVE_DOUBLE);
  }
  // The scoop mesh the run used (root attribute scoop_mesh), drawn at /scoop/pose. A run moved
  // since, or a mesh no longer there, draws no scoop and says so once.
  dem::TriangleMesh scoop_mesh;
  const std::string scoop_path = StringAttribute(root.id, "scoop_mesh");
  if (!scoop_path.empty() && !scoop_pose.empty()) {
    try {
      scoop_mesh = sim::LoadMesh(scoop_path);
    } catch (const sim::InputError& e) {
      std::fprintf(stderr, "scoopsim render: no scoop in the frames: %s\n", e.what());
    }
  }

  dem::Particles particles;
  int written = 0;
  const bool tty = isatty(fileno(stderr)) != 0;
  for (const std::string& name : names) {
    const std::string base = "/snapshots/" + name;
    const Id snapshot{H5Gopen2(file.id, base.c_str(), H5P_DEFAULT), H5Gclose};
    if (snapshot.id < 0) continue;
    const double time = DoubleAttribute(snapshot.id, "time", 0.0);
    size_t n = 0;
    const std::vector<double> x =
        Read<double>(h5_path, file.id, base + "/position", H5T_NATIVE_DOUBLE, &n);
    const std::vector<double> v =
        Read<double>(h5_path, file.id, base + "/velocity", H5T_NATIVE_DOUBLE);
    particles.radius = Read<double>(h5_path, file.id, base + "/radius", H5T_NATIVE_DOUBLE);
    particles.material = Read<int32_t>(h5_path, file.id, base + "/material", H5T_NATIVE_INT32);
    particles.id = Read<int64_t>(h5_path, file.id, base + "/id", H5T_NATIVE_INT64);
    if (x.size() != 3 * n || v.size() != 3 * n || particles.radius.size() != n ||
        particles.material.size() != n || particles.id.size() != n) {
      throw sim::InputError(h5_path + ": " + base + ": particle datasets differ in length");
    }
    particles.x.resize(n);
    particles.v.resize(n);
    for (size_t i = 0; i < n; ++i) {
      particles.x[i] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
      particles.v[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    }

    sim::WorldView view;
    view.time = time;
    view.particles = &particles;
    if (has_box) {
      view.box_min = box_lo;
      view.box_max = box_hi;
    } else {
      view.box_min = {1e300, 1e300, 1e300};
      view.box_max = {-1e300, -1e300, -1e300};
      for (size_t i = 0; i < n; ++i) {
        const double r = particles.radius[i];
        const dem::Vec3& p = particles.x[i];
        view.box_min = {std::min(view.box_min.x, p.x - r), std::min(view.box_min.y, p.y - r),
                        std::min(view.box_min.z, p.z - r)};
        view.box_max = {std::max(view.box_max.x, p.x + r), std::max(view.box_max.y, p.y + r),
                        std::max(view.box_max.z, p.z + r)};
      }
    }
    if (!scoop_time.empty()) {
      // The last scoop sample at or before the snapshot (1e-9 s slack for rounding).
      const auto it = std::upper_bound(scoop_time.begin(), scoop_time.end(), time + 1e-9);
      if (it != scoop_time.begin()) {
        const size_t k = static_cast<size_t>(it - scoop_time.begin()) - 1;
        if (k < scoop_pass.size()) view.pass = static_cast<int>(std::lround(scoop_pass[k]));
        if (k < scoop_rho.size()) view.rho = scoop_rho[k];
        if (!scoop_mesh.triangles.empty() && 7 * k + 6 < scoop_pose.size()) {
          const double* q = &scoop_pose[7 * k];
          view.meshes.push_back({&scoop_mesh, {{q[0], q[1], q[2]}, {q[3], q[4], q[5], q[6]}}});
        }
        if (3 * k + 2 < scoop_force.size()) {
          view.force =
              dem::Norm({scoop_force[3 * k], scoop_force[3 * k + 1], scoop_force[3 * k + 2]});
        }
      }
    }
    frames->Add(view);
    ++written;
    // A live line on a terminal; a line every 50 frames (and the last) otherwise.
    if (!quiet && tty) {
      std::fprintf(stderr, "\rscoopsim render: frame %d/%zu (t = %.5f s)", written, names.size(),
                   time);
    } else if (!quiet && (written % 50 == 0 || written == static_cast<int>(names.size()))) {
      std::fprintf(stderr, "scoopsim render: frame %d/%zu (t = %.5f s)\n", written, names.size(),
                   time);
    }
  }
  if (!quiet && tty) std::fprintf(stderr, "\n");
  return written;
}

}  // namespace render

#include "sim/files/h5_output.h"

#include <fcntl.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "sim/files/internal_h5.h"
#include "sim/input/scene.h"

namespace sim {
namespace h5 {

// ---------------------------------------------------------------------------------------------
// Shared helpers (declared in sim/files/internal_h5.h).

hid_t CheckId(hid_t id, const std::string& what) {
  if (id < 0) throw std::runtime_error("HDF5: " + what + " failed");
  return id;
}

void CheckOk(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: " + what + " failed");
}

void MakeParentFolders(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) {
    throw InputError(path + ": cannot create the folder " + parent.string() + ": " + ec.message());
  }
}

namespace {

// Sets on a group (or file) creation list: links in the header up to `links`, room for them.
void SetCompactLinks(hid_t plist, unsigned links) {
  links = std::clamp(links, 2u, 65535u);
  CheckOk(H5Pset_link_phase_change(plist, links, links - 1), "H5Pset_link_phase_change");
  CheckOk(H5Pset_est_link_info(plist, links, 16), "H5Pset_est_link_info");
}

}  // namespace

Handle CreateFile(const std::string& path, bool swmr, bool* got_swmr, const std::string& name) {
  if (got_swmr != nullptr) *got_swmr = false;
  MakeParentFolders(path);
  // Every call is checked and reported on one line: HDF5's own stack print would bury it (a full
  // disk printed hundreds of lines).
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  // Strong close: H5Fclose really closes the file, so "closed" means "complete on disk".
  Handle fapl(CheckId(H5Pcreate(H5P_FILE_ACCESS), "H5Pcreate"), H5Pclose);
  CheckOk(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG), "H5Pset_fclose_degree");
  // The root group's links in its header (GroupGcpl), and so those of the groups made under it
  // as intermediate groups.
  Handle fcpl(CheckId(H5Pcreate(H5P_FILE_CREATE), "H5Pcreate"), H5Pclose);
  SetCompactLinks(fcpl.get(), kGroupLinks);
  // Every file through the clean-header driver: after a failed write (a full disk) it drops the
  // later ones, so HDF5 can still close the file (a close that fails leaves the library half shut
  // down, and its exit handler crashed: SIGSEGV in H5F__close_cb).
  CheckOk(H5Pset_driver(fapl.get(), CleanHeaderDriver(), nullptr), "H5Pset_driver");
  hid_t file = H5I_INVALID_HID;
  if (swmr) {
    // SWMR needs the 1.10 file format. If the file system refuses (no file locking), fall back
    // to the same format without SWMR.
    CheckOk(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST),
            "H5Pset_libver_bounds");
    H5E_BEGIN_TRY {
      file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC | H5F_ACC_SWMR_WRITE, fcpl.get(), fapl.get());
    }
    H5E_END_TRY;
    if (file >= 0 && got_swmr != nullptr) *got_swmr = true;
  }
  if (file < 0) {
    H5E_BEGIN_TRY { file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()); }
    H5E_END_TRY;
  }
  if (file < 0) {
    // HDF5 does not say why; ask the C library whether the file can be made, and written (a full
    // disk is a failed write, not bad input).
    const std::string& shown = name.empty() ? path : name;
    std::string reason = "HDF5 could not create it";
    errno = 0;
    if (std::FILE* probe = std::fopen(path.c_str(), "wb")) {
      const char block[4096] = {};
      const bool written =
          std::fwrite(block, 1, sizeof block, probe) == sizeof block && std::fflush(probe) == 0;
      const int error = errno;
      std::fclose(probe);
      if (!written) throw OutputError(shown + ": write failed (" + std::strerror(error) + ")");
    } else if (errno != 0) {
      reason = std::strerror(errno);
    }
    throw InputError(shown + ": cannot create the output file: " + reason);
  }
  return Handle(file, H5Fclose);
}

void WriteNewFile(hid_t file, const std::string& name, const std::function<void()>& write) {
  const CleanDriverState* state = CleanDriverStateOf(file);
  try {
    write();
    CheckOk(H5Fflush(file, H5F_SCOPE_LOCAL), "H5Fflush " + name);
  } catch (const std::runtime_error&) {
    if (state == nullptr || !state->failed) throw;
  }
  if (state != nullptr && state->failed)
    throw OutputError(name + ": write failed (" + std::strerror(state->error) + ")");
}

Handle IntermediateGroupsLcpl() {
  Handle lcpl(CheckId(H5Pcreate(H5P_LINK_CREATE), "H5Pcreate"), H5Pclose);
  CheckOk(H5Pset_create_intermediate_group(lcpl.get(), 1), "H5Pset_create_intermediate_group");
  return lcpl;
}

Handle GroupGcpl(unsigned links) {
  Handle gcpl(CheckId(H5Pcreate(H5P_GROUP_CREATE), "H5Pcreate"), H5Pclose);
  SetCompactLinks(gcpl.get(), links);
  return gcpl;
}

void LinkWhenWritten(hid_t file, hid_t object, const std::string& path) {
  CheckOk(H5Fflush(file, H5F_SCOPE_LOCAL), "H5Fflush before linking " + path);
  CheckOk(H5Olink(object, file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT), "H5Olink " + path);
}

std::string ParentOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos || slash == 0 ? std::string("/") : path.substr(0, slash);
}

void MakeGroups(hid_t file, const std::string& path, unsigned links) {
  // Each prefix in turn ("/a", "/a/b", ...): its parent exists by then.
  for (size_t at = path.find('/', 1); ; at = path.find('/', at + 1)) {
    const std::string prefix = path.substr(0, at);
    if (!prefix.empty() && prefix != "/") {
      const htri_t exists = H5Lexists(file, prefix.c_str(), H5P_DEFAULT);
      CheckOk(exists, "H5Lexists " + prefix);
      if (exists == 0) {
        const Handle gcpl = GroupGcpl(links);
        const Handle group(
            CheckId(H5Gcreate_anon(file, gcpl.get(), H5P_DEFAULT), "H5Gcreate_anon " + prefix),
            H5Gclose);
        LinkWhenWritten(file, group.get(), prefix);
      }
    }
    if (at == std::string::npos) break;
  }
}

namespace {

// Replaces attribute `name` of `object` with a scalar of `file_type` read from `value`.
void ReplaceScalarAttribute(hid_t object, const std::string& name, hid_t file_type,
                            hid_t memory_type, const void* value) {
  const htri_t exists = H5Aexists(object, name.c_str());
  CheckOk(exists, "H5Aexists " + name);
  if (exists > 0) CheckOk(H5Adelete(object, name.c_str()), "H5Adelete " + name);
  Handle space(CheckId(H5Screate(H5S_SCALAR), "H5Screate"), H5Sclose);
  Handle attribute(
      CheckId(H5Acreate2(object, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              "H5Acreate2 " + name),
      H5Aclose);
  CheckOk(H5Awrite(attribute.get(), memory_type, value), "H5Awrite " + name);
}

Handle VariableStringType() {
  Handle type(CheckId(H5Tcopy(H5T_C_S1), "H5Tcopy"), H5Tclose);
  CheckOk(H5Tset_size(type.get(), H5T_VARIABLE), "H5Tset_size");
  CheckOk(H5Tset_cset(type.get(), H5T_CSET_UTF8), "H5Tset_cset");
  return type;
}

std::string XmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

std::string FormatDouble(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

void WriteStringAttribute(hid_t object, const std::string& name, const std::string& value) {
  Handle type = VariableStringType();
  const char* data = value.c_str();
  ReplaceScalarAttribute(object, name, type.get(), type.get(), &data);
}

void WriteDoubleAttribute(hid_t object, const std::string& name, double value) {
  ReplaceScalarAttribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void WriteU64Attribute(hid_t object, const std::string& name, uint64_t value) {
  ReplaceScalarAttribute(object, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, &value);
}

std::string HexHash(uint64_t hash) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

void WriteStateHash(hid_t object, uint64_t hash) {
  WriteStringAttribute(object, "state_hash", HexHash(hash));
  WriteU64Attribute(object, "state_hash_u64", hash);
}

std::string ReadStringAttribute(hid_t object, const std::string& name) {
  Handle attribute(CheckId(H5Aopen(object, name.c_str(), H5P_DEFAULT), "H5Aopen " + name),
                   H5Aclose);
  Handle file_type(CheckId(H5Aget_type(attribute.get()), "H5Aget_type " + name), H5Tclose);
  if (H5Tget_class(file_type.get()) != H5T_STRING) {
    throw std::runtime_error("HDF5: attribute " + name + " is not a string");
  }
  Handle memory_type(CheckId(H5Tcopy(file_type.get()), "H5Tcopy"), H5Tclose);
  if (H5Tis_variable_str(file_type.get()) > 0) {
    char* data = nullptr;
    CheckOk(H5Aread(attribute.get(), memory_type.get(), &data), "H5Aread " + name);
    std::string value = data != nullptr ? data : "";
    H5free_memory(data);
    return value;
  }
  std::string value(H5Tget_size(file_type.get()), '\0');
  CheckOk(H5Aread(attribute.get(), memory_type.get(), value.data()), "H5Aread " + name);
  return value.substr(0, value.find('\0'));
}

void WriteDatasetAttribute(hid_t location, const std::string& dataset, const std::string& attribute,
                           const std::string& value) {
  Handle object(CheckId(H5Oopen(location, dataset.c_str(), H5P_DEFAULT), "H5Oopen " + dataset),
                H5Oclose);
  WriteStringAttribute(object.get(), attribute, value);
}

void MarkQuaternions(hid_t location, const std::string& dataset, bool pose) {
  WriteDatasetAttribute(location, dataset, "quaternion_order", kQuaternionOrder);
  if (pose) WriteDatasetAttribute(location, dataset, "columns", kPoseColumns);
}

void WriteArray(hid_t location, const std::string& name, hid_t file_type, hid_t memory_type,
                const void* data, hsize_t rows, hsize_t width) {
  const int rank = width == 1 ? 1 : 2;
  const hsize_t dims[2] = {rows, width};
  Handle space(CheckId(H5Screate_simple(rank, dims, nullptr), "H5Screate_simple"), H5Sclose);
  Handle dcpl(CheckId(H5Pcreate(H5P_DATASET_CREATE), "H5Pcreate"), H5Pclose);
  if (rows > 0) {
    const hsize_t chunk[2] = {std::min(rows, kSnapshotChunkRows), width};
    CheckOk(H5Pset_chunk(dcpl.get(), rank, chunk), "H5Pset_chunk");
    CheckOk(H5Pset_shuffle(dcpl.get()), "H5Pset_shuffle");
    CheckOk(H5Pset_deflate(dcpl.get(), 4), "H5Pset_deflate");
  }
  Handle dataset(CheckId(H5Dcreate2(location, name.c_str(), file_type, space.get(), H5P_DEFAULT,
                                    dcpl.get(), H5P_DEFAULT),
                         "H5Dcreate2 " + name),
                 H5Dclose);
  if (rows > 0) {
    CheckOk(H5Dwrite(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
            "H5Dwrite " + name);
  }
}

void WriteBytes(hid_t location, const std::string& name, const std::vector<char>& bytes) {
  WriteArray(location, name, H5T_STD_U8LE, H5T_NATIVE_UCHAR, bytes.data(), bytes.size(), 1);
}

std::vector<size_t> IdOrder(const dem::Particles& particles) {
  const std::vector<int64_t>& id = particles.id;
  std::vector<size_t> order(id.size());
  std::iota(order.begin(), order.end(), size_t{0});
  if (!std::is_sorted(id.begin(), id.end())) {
    std::sort(order.begin(), order.end(), [&id](size_t a, size_t b) { return id[a] < id[b]; });
  }
  return order;
}

std::string SnapshotGroupName(int64_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "/snapshots/%06lld", static_cast<long long>(index));
  return name;
}

void MakeSnapshotsGroup(hid_t file, int64_t capacity) {
  if (H5Lexists(file, "/snapshots", H5P_DEFAULT) > 0) return;
  MakeGroups(file, "/snapshots", static_cast<unsigned>(std::min<int64_t>(capacity, 65535)));
}

int64_t SnapshotsCapacity(hid_t file) {
  htri_t exists = -1;
  H5E_BEGIN_TRY { exists = H5Lexists(file, "/snapshots", H5P_DEFAULT); }
  H5E_END_TRY;
  if (exists <= 0) return 0;
  const Handle group(CheckId(H5Gopen2(file, "/snapshots", H5P_DEFAULT), "H5Gopen2 /snapshots"),
                     H5Gclose);
  const Handle gcpl(CheckId(H5Gget_create_plist(group.get()), "H5Gget_create_plist"), H5Pclose);
  unsigned links = 0, name_length = 0;
  CheckOk(H5Pget_est_link_info(gcpl.get(), &links, &name_length), "H5Pget_est_link_info");
  return links;
}

Handle MakeParticleSnapshot(hid_t file, int64_t index, double time, const dem::Particles& p,
                            SnapshotEntry* made) {
  const size_t n = p.size();
  if (p.x.size() != n || p.v.size() != n || p.w.size() != n || p.radius.size() != n ||
      p.material.size() != n) {
    throw std::invalid_argument("WriteParticleSnapshot: particle arrays differ in length");
  }
  SnapshotEntry& entry = *made;
  entry = SnapshotEntry{SnapshotGroupName(index), time, static_cast<int64_t>(n), {}};
  const Handle gcpl = GroupGcpl(kSnapshotLinks);
  Handle group(CheckId(H5Gcreate_anon(file, gcpl.get(), H5P_DEFAULT), "H5Gcreate_anon " + entry.group),
               H5Gclose);
  WriteDoubleAttribute(group.get(), "time", time);

  // Gather every field in persistent-id order into one scratch buffer, then write it.
  const std::vector<size_t> order = IdOrder(p);
  std::vector<int64_t> ints(n);
  for (size_t k = 0; k < n; ++k) ints[k] = p.id[order[k]];
  WriteArray(group.get(), "id", H5T_STD_I64LE, H5T_NATIVE_INT64, ints.data(), n, 1);
  for (size_t k = 0; k < n; ++k) ints[k] = static_cast<int64_t>(k);
  WriteArray(group.get(), "connectivity", H5T_STD_I64LE, H5T_NATIVE_INT64, ints.data(), n, 1);

  std::vector<double> buffer(3 * n);
  auto write_vectors = [&](const char* name, const std::vector<dem::Vec3>& field) {
    for (size_t k = 0; k < n; ++k) {
      const dem::Vec3& a = field[order[k]];
      buffer[3 * k + 0] = a.x;
      buffer[3 * k + 1] = a.y;
      buffer[3 * k + 2] = a.z;
    }
    WriteArray(group.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buffer.data(), n, 3);
  };
  write_vectors("position", p.x);
  write_vectors("velocity", p.v);
  write_vectors("angular_velocity", p.w);

  for (size_t k = 0; k < n; ++k) buffer[k] = p.radius[order[k]];
  WriteArray(group.get(), "radius", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buffer.data(), n, 1);
  for (size_t k = 0; k < n; ++k) buffer[k] = dem::Norm(p.v[order[k]]);
  WriteArray(group.get(), "speed", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buffer.data(), n, 1);

  std::vector<int32_t> material(n);
  for (size_t k = 0; k < n; ++k) material[k] = p.material[order[k]];
  WriteArray(group.get(), "material", H5T_STD_I32LE, H5T_NATIVE_INT32, material.data(), n, 1);
  // 1 = integrated, 0 = sleeping (dem::SleepConfig); all 1 when sleeping is off or the state
  // carries no flags (a state assembled outside dem::System).
  const bool flagged = p.awake.size() == n;
  for (size_t k = 0; k < n; ++k) material[k] = !flagged || p.awake[order[k]] != 0;
  WriteArray(group.get(), "awake", H5T_STD_I32LE, H5T_NATIVE_INT32, material.data(), n, 1);
  return group;
}

SnapshotEntry WriteParticleSnapshot(hid_t file, int64_t index, double time,
                                    const dem::Particles& p) {
  SnapshotEntry entry;
  const Handle group = MakeParticleSnapshot(file, index, time, p, &entry);
  MakeGroups(file, ParentOf(entry.group), kGroupLinks);
  LinkWhenWritten(file, group.get(), entry.group);
  return entry;
}

std::string XdmfPath(const std::string& h5_path) {
  return std::filesystem::path(h5_path).replace_extension(".xdmf").string();
}

void WriteXdmf(const std::string& h5_path, const std::vector<SnapshotEntry>& snapshots) {
  // Data paths are relative to the sidecar's folder, which is the HDF5 file's folder.
  const std::string file = XmlEscape(std::filesystem::path(h5_path).filename().string());
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const SnapshotEntry& s : snapshots) {
    const std::string n = std::to_string(s.count);
    auto item = [&](const std::string& dims, const char* number_type, int precision,
                    const char* dataset) {
      std::ostringstream d;
      d << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"" << number_type
        << "\" Precision=\"" << precision << "\" Format=\"HDF\">" << file << ":" << s.group << "/"
        << dataset << "</DataItem>";
      return d.str();
    };
    auto attribute = [&](const char* name, const char* type, const std::string& dims,
                         const char* number_type, int precision) {
      x << "        <Attribute Name=\"" << name << "\" AttributeType=\"" << type
        << "\" Center=\"Node\">\n"
        << "          " << item(dims, number_type, precision, name) << "\n"
        << "        </Attribute>\n";
    };
    x << "      <Grid Name=\"" << s.group.substr(s.group.rfind('/') + 1)
      << "\" GridType=\"Uniform\">\n"
      << "        <Time Value=\"" << FormatDouble(s.time) << "\"/>\n"
      << "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
      << "\" NodesPerElement=\"1\">\n"
      << "          " << item(n, "Int", 8, "connectivity") << "\n"
      << "        </Topology>\n"
      << "        <Geometry GeometryType=\"XYZ\">\n"
      << "          " << item(n + " 3", "Float", 8, "position") << "\n"
      << "        </Geometry>\n";
    attribute("radius", "Scalar", n, "Float", 8);
    attribute("speed", "Scalar", n, "Float", 8);
    attribute("id", "Scalar", n, "Int", 8);
    attribute("material", "Scalar", n, "Int", 4);
    attribute("awake", "Scalar", n, "Int", 4);
    attribute("velocity", "Vector", n + " 3", "Float", 8);
    attribute("angular_velocity", "Vector", n + " 3", "Float", 8);
    x << "      </Grid>\n";
  }
  x << "    </Grid>\n"
    << MeshGridsXdmf(file, snapshots) << "  </Domain>\n"
    << "</Xdmf>\n";

  const std::string path = XdmfPath(h5_path);
  const std::string temporary = path + ".tmp";
  const std::string text = x.str();
  errno = 0;
  std::FILE* out = std::fopen(temporary.c_str(), "wb");
  bool written = out != nullptr && std::fwrite(text.data(), 1, text.size(), out) == text.size();
  int error = errno;
  if (out != nullptr && std::fclose(out) != 0 && written) {
    written = false;
    error = errno;
  }
  if (!written) {
    std::remove(temporary.c_str());  // no stray sidecar
    throw std::runtime_error(path + ": write failed (" + std::strerror(error != 0 ? error : EIO) +
                             ")");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    throw std::runtime_error(path + ": cannot replace the XDMF sidecar: " + std::strerror(errno));
  }
}

}  // namespace h5

// ---------------------------------------------------------------------------------------------
// H5Output

namespace {

constexpr hsize_t kSeriesChunkRows = 1024;  // rows per chunk of a time series

// One appendable time series and its rows not yet written.
struct Series {
  h5::Handle dataset;
  int width = 0;
  hsize_t rows_on_disk = 0;            // written to the dataset
  hsize_t rows_flushed = 0;            // of which flushed to the file
  bool bits = false;                   // uint64 (bit masks) instead of float64
  std::vector<double> pending;         // buffered rows, row-major (pending rows x width)
  std::vector<uint64_t> pending_bits;  // the same for a uint64 series
  size_t PendingValues() const { return bits ? pending_bits.size() : pending.size(); }
};

}  // namespace

struct H5Output::Impl {
  std::string path;
  h5::Handle file;
  h5::Handle root;  // the root group, home of the attributes
  bool swmr = false;
  double flush_seconds = 10.0;
  std::chrono::steady_clock::time_point last_flush;
  std::map<std::string, Series, std::less<>> series;  // by absolute dataset path
  std::vector<h5::SnapshotEntry> snapshots;
  int64_t snapshot_capacity = 0;                 // room made in /snapshots (PlanSnapshots)
  std::string group;                             // SetGroup prefix ("" or "/name")
  h5::Handle group_obj;                          // that group, once an attribute was set on it
  int lock_fd = -1;                              // holds the write lock on the file until Close()
  int old_lock_fd = -1;                          // and on the file it replaced (PutInPlace)
  const h5::CleanDriverState* driver = nullptr;  // what the file driver saw (CreateFile's)
  std::string failure;                           // why writing failed; then nothing more is written
  bool flush_due = false;                        // a series holds a chunk's worth of rows
  // String attributes of series, by dataset path, written when the dataset is made.
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> series_attributes;

  // Runs a write; on the first failure, records the one-line reason (which file, how much is in
  // it, what it keeps) and throws it as OutputError. After a failure every write throws it again.
  // The driver is asked too: HDF5 does not report every failed write (a failure while closing
  // a dataset handle is lost).
  template <typename F>
  void Write(F&& write) {
    if (!failure.empty()) throw OutputError(failure);
    try {
      write();
    } catch (const std::exception& e) {
      failure = Describe(e.what());
      throw OutputError(failure);
    }
    if (driver != nullptr && driver->failed) {
      failure = Describe("");
      throw OutputError(failure);
    }
  }

  std::string Describe(const std::string& what) const {
    const h5::CleanDriverState state = driver != nullptr ? *driver : h5::CleanDriverState{};
    std::string message = path + ": ";
    if (state.failed) {
      char size[64];
      std::snprintf(size, sizeof size, "%.3g MB", state.file_size / 1e6);
      message += std::string("write failed (") + std::strerror(state.error) + ") with " + size +
                 " in the file";
    } else {
      message += what;
    }
    // What the file keeps: the longest series as of the last complete flush.
    const Series* longest = nullptr;
    const std::string* name = nullptr;
    for (const auto& [n, s] : series) {  // ties: a */time series
      const bool time = IsTime(n);
      if (longest == nullptr || s.rows_flushed > longest->rows_flushed ||
          (s.rows_flushed == longest->rows_flushed && time)) {
        longest = &s;
        name = &n;
      }
    }
    if (longest != nullptr) {
      message += "; it keeps the rows of the last flush (" + std::to_string(longest->rows_flushed) +
                 " of " + *name + ")";
    }
    return message;
  }

  // Where attributes go: the SetGroup group (created on first use) or the root.
  hid_t AttributeTarget() {
    if (group.empty()) return root.get();
    if (!group_obj.valid()) {
      htri_t exists = -1;
      H5E_BEGIN_TRY { exists = H5Lexists(file.get(), group.c_str(), H5P_DEFAULT); }
      H5E_END_TRY;
      if (exists > 0) {
        group_obj = h5::Handle(
            h5::CheckId(H5Gopen2(file.get(), group.c_str(), H5P_DEFAULT), "H5Gopen2 " + group),
            H5Gclose);
      } else {
        h5::MakeGroups(file.get(), group, h5::kGroupLinks);
        group_obj = h5::Handle(
            h5::CheckId(H5Gopen2(file.get(), group.c_str(), H5P_DEFAULT), "H5Gopen2 " + group),
            H5Gclose);
      }
    }
    return group_obj.get();
  }

  void RequireOpen(const char* what) const {
    if (!file.valid()) throw std::logic_error(std::string("H5Output::") + what + ": file closed");
  }

  Series& GetSeries(const std::string& name, int width, bool bits = false) {
    auto it = series.find(name);
    if (it != series.end()) {
      if (it->second.width != width || it->second.bits != bits) {
        throw std::invalid_argument("H5Output::AppendRow: " + name + " has width " +
                                    std::to_string(it->second.width) +
                                    (it->second.bits ? " (uint64)" : " (float64)") + ", got " +
                                    std::to_string(width) + (bits ? " (uint64)" : " (float64)"));
      }
      return it->second;
    }
    // Extendable (n) or (n x width), 1024-row chunks, shuffle + deflate 4. The chunk at the end
    // stays unfiltered until full: see the crash-safety note in h5_output.h.
    const int rank = width == 1 ? 1 : 2;
    const hsize_t w = static_cast<hsize_t>(width);
    const hsize_t dims[2] = {0, w};
    const hsize_t max_dims[2] = {H5S_UNLIMITED, w};
    const hsize_t chunk[2] = {kSeriesChunkRows, w};
    h5::Handle space(h5::CheckId(H5Screate_simple(rank, dims, max_dims), "H5Screate_simple"),
                     H5Sclose);
    h5::Handle dcpl(h5::CheckId(H5Pcreate(H5P_DATASET_CREATE), "H5Pcreate"), H5Pclose);
    h5::CheckOk(H5Pset_chunk(dcpl.get(), rank, chunk), "H5Pset_chunk");
    h5::CheckOk(H5Pset_shuffle(dcpl.get()), "H5Pset_shuffle");
    h5::CheckOk(H5Pset_deflate(dcpl.get(), 4), "H5Pset_deflate");
    h5::CheckOk(H5Pset_chunk_opts(dcpl.get(), H5D_CHUNK_DONT_FILTER_PARTIAL_CHUNKS),
                "H5Pset_chunk_opts");
    // Made unlinked, its attributes written, then linked once on disk (h5::LinkWhenWritten).
    h5::MakeGroups(file.get(), h5::ParentOf(name), h5::kGroupLinks);
    Series s;
    s.dataset = h5::Handle(
        h5::CheckId(H5Dcreate_anon(file.get(), bits ? H5T_STD_U64LE : H5T_IEEE_F64LE, space.get(),
                                   dcpl.get(), H5P_DEFAULT),
                    "H5Dcreate_anon " + name + " in " + path),
        H5Dclose);
    s.width = width;
    s.bits = bits;
    if (bits) {
      s.pending_bits.reserve(kSeriesChunkRows * w);
    } else {
      s.pending.reserve(kSeriesChunkRows * w);
    }
    for (const auto& [attribute, value] : series_attributes[name])
      h5::WriteStringAttribute(s.dataset.get(), attribute, value);
    h5::LinkWhenWritten(file.get(), s.dataset.get(), name);
    return series.emplace(name, std::move(s)).first->second;
  }

  // Appends the buffered rows of `s` to its dataset.
  void WriteRows(const std::string& name, Series& s) {
    const hsize_t w = static_cast<hsize_t>(s.width);
    const hsize_t n = s.PendingValues() / w;
    if (n == 0) return;
    const int rank = s.width == 1 ? 1 : 2;
    const hsize_t new_dims[2] = {s.rows_on_disk + n, w};
    const std::string what = " " + name + " in " + path;
    h5::CheckOk(H5Dset_extent(s.dataset.get(), new_dims), "H5Dset_extent" + what);
    h5::Handle file_space(h5::CheckId(H5Dget_space(s.dataset.get()), "H5Dget_space" + what),
                          H5Sclose);
    const hsize_t start[2] = {s.rows_on_disk, 0};
    const hsize_t count[2] = {n, w};
    h5::CheckOk(
        H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr),
        "H5Sselect_hyperslab" + what);
    h5::Handle memory_space(h5::CheckId(H5Screate_simple(rank, count, nullptr), "H5Screate"),
                            H5Sclose);
    h5::CheckOk(H5Dwrite(s.dataset.get(), s.bits ? H5T_NATIVE_UINT64 : H5T_NATIVE_DOUBLE,
                         memory_space.get(), file_space.get(), H5P_DEFAULT,
                         s.bits ? static_cast<const void*>(s.pending_bits.data())
                                : static_cast<const void*>(s.pending.data())),
                "H5Dwrite" + what);
    s.rows_on_disk += n;
    s.pending.clear();
    s.pending_bits.clear();
  }

  // Takes from the file now at `path` the first cursor.rows of each series (buffered, written at
  // the next flush) and the first cursor.snapshot_time.size() snapshots (a run resumed from its
  // checkpoint). Copied value by value: H5Ocopy into a file in SWMR mode fails in HDF5 1.10.
  void CopyUpTo(const OutputCursor& cursor) {
    const h5::Handle old = h5::OpenForReading(path, false);
    const h5::Reader in(path, old.get());
    auto width_of = [&](const std::string& name) -> hsize_t {
      if (!in.Exists(name)) in.Fail(name, "missing; cannot resume from this file");
      const h5::Handle d(h5::CheckId(H5Dopen2(old.get(), name.c_str(), H5P_DEFAULT), name),
                         H5Dclose);
      const h5::Handle space(h5::CheckId(H5Dget_space(d.get()), name), H5Sclose);
      hsize_t dims[2] = {0, 1};
      return H5Sget_simple_extent_dims(space.get(), dims, nullptr) == 2 ? dims[1] : 1;
    };
    for (const auto& [name, rows] : cursor.rows) {
      const hsize_t width = width_of(name);
      const h5::Handle d(h5::CheckId(H5Dopen2(old.get(), name.c_str(), H5P_DEFAULT), name),
                         H5Dclose);
      const h5::Handle type(h5::CheckId(H5Dget_type(d.get()), name), H5Tclose);
      const bool bits = H5Tget_class(type.get()) == H5T_INTEGER;
      // Its string attributes (quaternion_order, ...) go with it, written as it is made: in SWMR
      // mode a dataset's header does not grow once rows are in it.
      std::vector<std::string> attributes;
      hsize_t at = 0;
      H5Aiterate2(
          d.get(), H5_INDEX_NAME, H5_ITER_INC, &at,
          [](hid_t, const char* attribute, const H5A_info_t*, void* data) -> herr_t {
            static_cast<std::vector<std::string>*>(data)->push_back(attribute);
            return 0;
          },
          &attributes);
      for (const std::string& attribute : attributes) {
        const h5::Handle a(H5Aopen(d.get(), attribute.c_str(), H5P_DEFAULT), H5Aclose);
        const h5::Handle a_type(H5Aget_type(a.get()), H5Tclose);
        if (H5Tget_class(a_type.get()) != H5T_STRING) continue;
        series_attributes[name].emplace_back(attribute,
                                             h5::ReadStringAttribute(d.get(), attribute));
      }
      int64_t n = 0;
      const auto check_rows = [&] {
        if (n < rows)
          in.Fail(name, "holds " + std::to_string(n) + " rows, its checkpoint " +
                            std::to_string(rows) + "; cannot resume from this file");
      };
      Series& s = GetSeries(name, static_cast<int>(width), bits);
      const int64_t keep = rows * static_cast<int64_t>(width);
      if (bits) {
        const auto values = in.Read<uint64_t>(name, H5T_INTEGER, H5T_NATIVE_UINT64, -1, width, &n);
        check_rows();
        s.pending_bits.assign(values.begin(), values.begin() + keep);
      } else {
        const auto values = in.Read<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, width, &n);
        check_rows();
        s.pending.assign(values.begin(), values.begin() + keep);
      }
    }
    struct Field {
      const char* name;
      hid_t file_type, memory_type;
      hsize_t width;
    };
    const Field fields[] = {{"id", H5T_STD_I64LE, H5T_NATIVE_INT64, 1},
                            {"connectivity", H5T_STD_I64LE, H5T_NATIVE_INT64, 1},
                            {"position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3},
                            {"velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3},
                            {"angular_velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3},
                            {"radius", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1},
                            {"speed", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1},
                            {"material", H5T_STD_I32LE, H5T_NATIVE_INT32, 1},
                            {"awake", H5T_STD_I32LE, H5T_NATIVE_INT32, 1}};
    // /snapshots with the room the killed run made it with (h5::GroupGcpl).
    if (!cursor.snapshot_time.empty()) {
      snapshot_capacity = std::max<int64_t>(h5::SnapshotsCapacity(old.get()),
                                            static_cast<int64_t>(cursor.snapshot_time.size()));
      h5::MakeSnapshotsGroup(file.get(), snapshot_capacity);
    }
    const h5::Handle gcpl = h5::GroupGcpl(h5::kSnapshotLinks);
    for (size_t k = 0; k < cursor.snapshot_time.size(); ++k) {
      const std::string group_name = h5::SnapshotGroupName(static_cast<int64_t>(k));
      const int64_t count = cursor.snapshot_count[k];
      // Linked once whole (h5::LinkWhenWritten), as a run's own snapshots.
      const h5::Handle group(h5::CheckId(H5Gcreate_anon(file.get(), gcpl.get(), H5P_DEFAULT),
                                         "H5Gcreate_anon " + group_name),
                             H5Gclose);
      h5::WriteDoubleAttribute(group.get(), "time", cursor.snapshot_time[k]);
      for (const Field& f : fields) {
        const std::string name = group_name + "/" + f.name;
        if (f.memory_type == H5T_NATIVE_DOUBLE) {
          const std::vector<double> v =
              in.Read<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, count, f.width);
          h5::WriteArray(group.get(), f.name, f.file_type, f.memory_type, v.data(), count, f.width);
        } else if (f.memory_type == H5T_NATIVE_INT64) {
          const std::vector<int64_t> v =
              in.Read<int64_t>(name, H5T_INTEGER, H5T_NATIVE_INT64, count, f.width);
          h5::WriteArray(group.get(), f.name, f.file_type, f.memory_type, v.data(), count, f.width);
        } else {
          const std::vector<int32_t> v =
              in.Read<int32_t>(name, H5T_INTEGER, H5T_NATIVE_INT32, count, f.width);
          h5::WriteArray(group.get(), f.name, f.file_type, f.memory_type, v.data(), count, f.width);
        }
      }
      h5::SnapshotEntry entry{group_name, cursor.snapshot_time[k], count, {}};
      entry.meshes = CopyMeshes(in, group_name, group.get());
      h5::MakeGroups(file.get(), "/snapshots", h5::kGroupLinks);
      h5::LinkWhenWritten(file.get(), group.get(), group_name);
      snapshots.push_back(std::move(entry));
    }
  }

  // The meshes of snapshot `group` in the file read by `in` (sim/files/internal_h5.h,
  // WriteSnapshotMeshes), copied as they are into `into`, its copy (not yet linked).
  std::vector<h5::MeshEntry> CopyMeshes(const h5::Reader& in, const std::string& group,
                                        hid_t into) {
    std::vector<h5::MeshEntry> entries;
    for (const char* role : {"scoop", "arm", "obstacles"}) {
      const std::string at = group + "/meshes/" + role;
      if (!in.Exists(at)) continue;
      int64_t v = 0, t = 0, parts = 0;
      const auto points = in.Read<double>(at + "/points", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 3, &v);
      const auto tris =
          in.Read<int64_t>(at + "/triangles", H5T_INTEGER, H5T_NATIVE_INT64, -1, 3, &t);
      const auto part = in.Read<int32_t>(at + "/part", H5T_INTEGER, H5T_NATIVE_INT32, t, 1);
      const auto pose = in.Read<double>(at + "/pose", H5T_FLOAT, H5T_NATIVE_DOUBLE, -1, 7, &parts);
      const h5::Handle lcpl = h5::IntermediateGroupsLcpl();
      const h5::Handle gcpl = h5::GroupGcpl(h5::kGroupLinks);
      const std::string relative = std::string("meshes/") + role;
      const h5::Handle g(
          h5::CheckId(H5Gcreate2(into, relative.c_str(), lcpl.get(), gcpl.get(), H5P_DEFAULT),
                      "H5Gcreate2 " + at),
          H5Gclose);
      const hsize_t hv = static_cast<hsize_t>(v), ht = static_cast<hsize_t>(t);
      h5::WriteArray(g.get(), "points", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, points.data(), hv, 3);
      h5::WriteArray(g.get(), "triangles", H5T_STD_I64LE, H5T_NATIVE_INT64, tris.data(), ht, 3);
      h5::WriteArray(g.get(), "part", H5T_STD_I32LE, H5T_NATIVE_INT32, part.data(), ht, 1);
      h5::WriteArray(g.get(), "pose", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, pose.data(),
                     static_cast<hsize_t>(parts), 7);
      h5::MarkQuaternions(g.get(), "pose", true);
      entries.push_back({role, v, t});
    }
    return entries;
  }

  // Writes every series' buffered rows, each group's `time` last: the others first, then an
  // H5Fflush puts them on disk, then the times. No write extends two datasets at once, so a kill
  // inside a flush can leave a group's series of different lengths; this order makes `time` the
  // shortest, and its length the rows every series of the group holds in full (the readers cut
  // to it: h5::Reader::ReadSeries, docs/files.md "Crash-safe output"). The caller flushes again.
  void WriteAllRows() {
    bool times_pending = false;
    for (auto& [name, s] : series) {
      if (IsTime(name)) {
        times_pending = times_pending || s.PendingValues() > 0;
      } else {
        WriteRows(name, s);
      }
    }
    if (!times_pending) return;
    h5::CheckOk(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "H5Fflush " + path);
    for (auto& [name, s] : series)
      if (IsTime(name)) WriteRows(name, s);
  }
  static bool IsTime(const std::string& name) {
    return name.size() >= 5 && name.compare(name.size() - 5, 5, "/time") == 0;
  }
};

namespace {

// Takes a write lock a second writer cannot get on the file `fd` is open on: an
// open-file-description lock (fcntl F_OFD_SETLK), which HDF5's own flock() locks do not meet and
// which no close() of another descriptor of the file releases. False if another process holds
// it; a file system without such locks counts as unlocked.
bool LockFile(int fd) {
  struct flock lock {};
  lock.l_type = F_WRLCK;
  lock.l_whence = SEEK_SET;
  return ::fcntl(fd, F_OFD_SETLK, &lock) == 0 || (errno != EAGAIN && errno != EACCES);
}

std::string AnotherWriter(const std::string& path) {
  return path +
         ": another process (a scoopsim run?) is writing this file; give this run another -o";
}

// Opens the file at `path` for the lock (-1 with errno when it cannot be opened: ENOENT when it
// is not there); throws sim::InputError when it is not a regular file (a device, a FIFO, a
// folder), which an output would replace. Opened without blocking and without becoming the
// controlling terminal, then checked again (the name may have changed in between).
int OpenOldOutput(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  if (S_ISREG(st.st_mode)) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0 || (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode))) return fd;
    ::close(fd);  // something else took the name meanwhile
  }
  const char* kind = S_ISDIR(st.st_mode)    ? "a folder"
                     : S_ISCHR(st.st_mode)  ? "a character device"
                     : S_ISBLK(st.st_mode)  ? "a block device"
                     : S_ISFIFO(st.st_mode) ? "a FIFO (named pipe)"
                     : S_ISSOCK(st.st_mode) ? "a socket"
                                            : "not a regular file";
  throw InputError(path + ": expected a regular file or a new path to write the output, got " +
                   kind);
}

// Puts the new file `temporary` (written, flushed and locked by this process) in place at
// `path`, refusing when another process writes `path`: a new name is taken with link() (fails if
// the name exists), an existing file is locked first, then replaced with rename(); either step
// is atomic, so `path` is always an old file or the new one, never a half-made one. Returns the
// descriptor holding the lock on the replaced file (-1 if none), kept until Close() so that a
// process which opened it before the rename cannot take it over.
int PutInPlace(const std::string& temporary, const std::string& path) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    if (::link(temporary.c_str(), path.c_str()) == 0) {
      ::unlink(temporary.c_str());
      return -1;
    }
    if (errno != EEXIST && errno != EPERM && errno != ENOTSUP) break;
    const int old = OpenOldOutput(path);
    if (old < 0 && errno == ENOENT) continue;  // gone meanwhile: take the name again
    if (old < 0) break;
    if (!LockFile(old)) {
      ::close(old);
      throw InputError(AnotherWriter(path));
    }
    if (::rename(temporary.c_str(), path.c_str()) == 0) return old;
    ::close(old);
    break;
  }
  throw InputError(path + ": cannot create the output file: " + std::strerror(errno));
}

}  // namespace

void CheckOutputPath(const std::string& path) {
  const int fd = OpenOldOutput(path);
  if (fd < 0) return;  // a new path (or one the write will say why it cannot take)
  const bool free = LockFile(fd);
  ::close(fd);  // (releases the lock: the only descriptor of its open file description)
  if (!free) throw InputError(AnotherWriter(path));
}

void PlaceOutput(const std::string& temporary, const std::string& path) {
  try {
    const int old = PutInPlace(temporary, path);
    if (old >= 0) ::close(old);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

H5Output::H5Output(const std::string& path, const std::string& scene_yaml,
                   const std::string& version, double flush_seconds, const OutputCursor* resume)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  m.flush_seconds = flush_seconds;
  // Made under a name of this process, then put in place: a run killed at any moment leaves the
  // old file or a valid new one at `path`, and a second writer of `path` is refused.
  const std::string temporary = path + "." + std::to_string(::getpid()) + ".new";
  try {
    m.file = h5::CreateFile(temporary, /*swmr=*/true, &m.swmr, path);
    m.driver = h5::CleanDriverStateOf(m.file.get());
    m.root =
        h5::Handle(h5::CheckId(H5Gopen2(m.file.get(), "/", H5P_DEFAULT), "H5Gopen2 /"), H5Gclose);
    h5::WriteStringAttribute(m.root.get(), "scene_yaml", scene_yaml);
    h5::WriteStringAttribute(m.root.get(), "version", version);
    if (resume != nullptr) m.CopyUpTo(*resume);
    Flush();  // a valid file from the start, even if the run is killed before its first flush
    m.lock_fd = ::open(temporary.c_str(), O_RDWR | O_CLOEXEC);
    if (m.lock_fd < 0 || !LockFile(m.lock_fd))
      throw InputError(temporary + ": cannot lock the new output file");
    m.old_lock_fd = PutInPlace(temporary, path);
    if (!m.snapshots.empty()) {
      h5::WriteXdmf(m.path, m.snapshots);
    } else {
      // An earlier run's sidecar would name snapshots this file does not have.
      std::error_code ignored;
      std::filesystem::remove(h5::XdmfPath(m.path), ignored);
    }
  } catch (...) {
    m.root.reset();
    m.file.reset();
    if (m.lock_fd >= 0) ::close(m.lock_fd);
    m.lock_fd = -1;
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    try {
      throw;
    } catch (const InputError& e) {  // name the file asked for, not the temporary one
      std::string message = e.what();
      if (message.compare(0, temporary.size(), temporary) == 0)
        message = path + message.substr(temporary.size());
      throw InputError(message);
    }
  }
}

H5Output::~H5Output() {
  try {
    Close();
  } catch (...) {
    // A destructor must not throw; Close() reports the error to callers that want it.
  }
}

namespace {

// The absolute path of `dataset` under the SetGroup prefix `group`.
std::string SeriesName(const std::string& group, const std::string& dataset) {
  return group + (!dataset.empty() && dataset[0] == '/' ? dataset : "/" + dataset);
}

}  // namespace

template <typename T>
void H5Output::Append(const std::string& dataset, const T* values, int width) {
  Impl& m = *impl_;
  constexpr bool kBits = std::is_same_v<T, uint64_t>;
  m.RequireOpen("AppendRow");
  if (width < 1) throw std::invalid_argument("H5Output::AppendRow: width must be >= 1");
  if (!m.failure.empty()) throw OutputError(m.failure);
  const std::string name = SeriesName(m.group, dataset);
  Series* s = nullptr;
  const auto it = m.series.find(name);
  if (it != m.series.end()) {
    s = &m.GetSeries(name, width, kBits);  // checks the width and type (std::invalid_argument)
  } else {
    m.Write([&] { s = &m.GetSeries(name, width, kBits); });  // creates the dataset
  }
  if constexpr (kBits) {
    s->pending_bits.insert(s->pending_bits.end(), values, values + width);
  } else {
    s->pending.insert(s->pending.end(), values, values + width);
  }
  // Rows go to the file only in Flush(), so the file's row counts move with its flushes; a
  // series that reaches its next chunk boundary makes the next MaybeFlush() flush (whole chunks
  // in one piece, and never between two series of one step's rows).
  const hsize_t to_boundary = kSeriesChunkRows - s->rows_on_disk % kSeriesChunkRows;
  if (s->PendingValues() / static_cast<size_t>(width) >= to_boundary) m.flush_due = true;
}

void H5Output::AppendRow(const std::string& dataset, const double* values, int width) {
  Append(dataset, values, width);
}

void H5Output::AppendRow(const std::string& dataset, const uint64_t* values, int width) {
  Append(dataset, values, width);
}

void H5Output::SetSeriesAttribute(const std::string& dataset, const std::string& name,
                                  const std::string& value) {
  Impl& m = *impl_;
  m.RequireOpen("SetSeriesAttribute");
  const std::string path = SeriesName(m.group, dataset);
  auto& list = m.series_attributes[path];
  for (const auto& [attribute, v] : list) {
    if (attribute == name && v == value) return;
  }
  list.emplace_back(name, value);
  const auto it = m.series.find(path);
  if (it != m.series.end()) {
    m.Write([&] { h5::WriteStringAttribute(it->second.dataset.get(), name, value); });
  }
}

void H5Output::WriteTable(const std::string& dataset, const std::vector<TableColumn>& columns,
                          int64_t rows) {
  Impl& m = *impl_;
  m.RequireOpen("WriteTable");
  if (!m.failure.empty()) throw OutputError(m.failure);
  const std::string name = SeriesName(m.group, dataset);
  m.Write([&] {
    // One packed record per row: float64, uint64, int32 or fixed-length (NUL-padded) text.
    std::vector<size_t> offset, size;
    size_t record = 0;
    for (const TableColumn& c : columns) {
      size_t bytes = 8;
      if (c.kind == TableColumn::Kind::kInt32) bytes = 4;
      if (c.kind == TableColumn::Kind::kText) {
        bytes = 1;
        for (const std::string& t : c.text) bytes = std::max(bytes, t.size() + 1);
      }
      offset.push_back(record);
      size.push_back(bytes);
      record += bytes;
    }
    h5::Handle type(h5::CheckId(H5Tcreate(H5T_COMPOUND, record), "H5Tcreate"), H5Tclose);
    std::vector<h5::Handle> strings;
    for (size_t k = 0; k < columns.size(); ++k) {
      hid_t member = H5T_NATIVE_DOUBLE;
      switch (columns[k].kind) {
        case TableColumn::Kind::kFloat64:
          member = H5T_NATIVE_DOUBLE;
          break;
        case TableColumn::Kind::kUint64:
          member = H5T_NATIVE_UINT64;
          break;
        case TableColumn::Kind::kInt32:
          member = H5T_NATIVE_INT32;
          break;
        case TableColumn::Kind::kText:
          strings.emplace_back(h5::CheckId(H5Tcopy(H5T_C_S1), "H5Tcopy"), H5Tclose);
          h5::CheckOk(H5Tset_size(strings.back().get(), size[k]), "H5Tset_size");
          h5::CheckOk(H5Tset_strpad(strings.back().get(), H5T_STR_NULLTERM), "H5Tset_strpad");
          member = strings.back().get();
          break;
      }
      h5::CheckOk(H5Tinsert(type.get(), columns[k].name.c_str(), offset[k], member), "H5Tinsert");
    }
    std::vector<unsigned char> data(record * static_cast<size_t>(rows), 0);
    for (int64_t r = 0; r < rows; ++r) {
      unsigned char* at = data.data() + record * static_cast<size_t>(r);
      for (size_t k = 0; k < columns.size(); ++k) {
        const TableColumn& c = columns[k];
        switch (c.kind) {
          case TableColumn::Kind::kFloat64:
            std::memcpy(at + offset[k], &c.float64.at(r), 8);
            break;
          case TableColumn::Kind::kUint64:
            std::memcpy(at + offset[k], &c.uint64.at(r), 8);
            break;
          case TableColumn::Kind::kInt32:
            std::memcpy(at + offset[k], &c.int32.at(r), 4);
            break;
          case TableColumn::Kind::kText:
            std::memcpy(at + offset[k], c.text.at(r).data(), c.text.at(r).size());
            break;
        }
      }
    }
    const hsize_t dims[1] = {static_cast<hsize_t>(rows)};
    h5::Handle space(h5::CheckId(H5Screate_simple(1, dims, nullptr), "H5Screate_simple"), H5Sclose);
    h5::MakeGroups(m.file.get(), h5::ParentOf(name), h5::kGroupLinks);
    h5::Handle d(h5::CheckId(H5Dcreate_anon(m.file.get(), type.get(), space.get(), H5P_DEFAULT,
                                            H5P_DEFAULT),
                             "H5Dcreate_anon " + name + " in " + m.path),
                 H5Dclose);
    if (rows > 0) {
      h5::CheckOk(H5Dwrite(d.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()),
                  "H5Dwrite " + name + " in " + m.path);
    }
    h5::LinkWhenWritten(m.file.get(), d.get(), name);
  });
}

void H5Output::WriteSnapshot(double time, const dem::Particles& particles,
                             const std::vector<MeshView>& meshes) {
  Impl& m = *impl_;
  m.RequireOpen("WriteSnapshot");
  const int64_t index = static_cast<int64_t>(m.snapshots.size());
  m.Write([&] {
    if (index == 0 && m.snapshot_capacity == 0) m.snapshot_capacity = kDefaultSnapshotCapacity;
    h5::MakeSnapshotsGroup(m.file.get(), m.snapshot_capacity);
    // Made whole out of the tree, then linked (h5::LinkWhenWritten).
    h5::SnapshotEntry entry;
    const h5::Handle group =
        h5::MakeParticleSnapshot(m.file.get(), index, time, particles, &entry);
    if (!meshes.empty()) entry.meshes = h5::WriteSnapshotMeshes(group.get(), meshes);
    h5::LinkWhenWritten(m.file.get(), group.get(), entry.group);
    m.snapshots.push_back(std::move(entry));
  });
  Flush();
  m.Write([&] { h5::WriteXdmf(m.path, m.snapshots); });
}

void H5Output::PlanSnapshots(int64_t count) {
  Impl& m = *impl_;
  // Room for a quarter more than planned; past it /snapshots goes on in dense storage.
  if (m.snapshots.empty()) m.snapshot_capacity = std::max<int64_t>(count + count / 4 + 16, 16);
}

void H5Output::SetStateHash(uint64_t hash) {
  impl_->RequireOpen("SetStateHash");
  impl_->Write([&] { h5::WriteStateHash(impl_->AttributeTarget(), hash); });
}

void H5Output::SetAttribute(const std::string& name, double value) {
  impl_->RequireOpen("SetAttribute");
  impl_->Write([&] { h5::WriteDoubleAttribute(impl_->AttributeTarget(), name, value); });
}

void H5Output::SetCountAttribute(const std::string& name, uint64_t value) {
  impl_->RequireOpen("SetCountAttribute");
  impl_->Write([&] { h5::WriteU64Attribute(impl_->AttributeTarget(), name, value); });
}

void H5Output::SetAttribute(const std::string& name, const std::string& value) {
  impl_->RequireOpen("SetAttribute");
  impl_->Write([&] { h5::WriteStringAttribute(impl_->AttributeTarget(), name, value); });
}

void H5Output::SetGroup(const std::string& group) {
  impl_->RequireOpen("SetGroup");
  std::string g = group;
  if (!g.empty() && g[0] != '/') g = "/" + g;
  while (g.size() > 1 && g.back() == '/') g.pop_back();
  if (g == "/") g.clear();
  impl_->group_obj.reset();
  impl_->group = g;
}

bool H5Output::MaybeFlush() {
  Impl& m = *impl_;
  if (!m.file.valid()) return false;
  const auto now = std::chrono::steady_clock::now();
  if (!m.flush_due && std::chrono::duration<double>(now - m.last_flush).count() < m.flush_seconds)
    return false;
  Flush();
  return true;
}

void H5Output::Flush() {
  Impl& m = *impl_;
  m.RequireOpen("Flush");
  m.Write([&] {
    m.WriteAllRows();
    h5::CheckOk(H5Fflush(m.file.get(), H5F_SCOPE_LOCAL), "H5Fflush " + m.path);
  });
  for (auto& [name, s] : m.series) s.rows_flushed = s.rows_on_disk;
  m.flush_due = false;
  m.last_flush = std::chrono::steady_clock::now();
}

void H5Output::Close() {
  Impl& m = *impl_;
  if (!m.file.valid()) return;
  // Write what is buffered, then close every handle even if writing failed. After a failure
  // nothing more is written: the file keeps what its last flush left.
  std::exception_ptr error;
  if (m.failure.empty()) {
    try {
      m.Write([&] {
        m.WriteAllRows();
        h5::CheckOk(H5Fflush(m.file.get(), H5F_SCOPE_LOCAL), "H5Fflush " + m.path);
      });
    } catch (...) {
      error = std::current_exception();
    }
  }
  m.series.clear();
  m.group_obj.reset();
  m.root.reset();
  m.driver = nullptr;
  const herr_t status = m.file.reset();
  for (int* fd : {&m.lock_fd, &m.old_lock_fd}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
  if (error) std::rethrow_exception(error);
  if (m.failure.empty() && status < 0) {
    m.failure = m.path + ": closing the file failed";
    throw OutputError(m.failure);
  }
}

bool H5Output::failed() const { return !impl_->failure.empty(); }

OutputCursor H5Output::Cursor() {
  Flush();
  OutputCursor c;
  for (const auto& [name, s] : impl_->series)
    c.rows.emplace_back(name, static_cast<int64_t>(s.rows_flushed));
  for (const h5::SnapshotEntry& e : impl_->snapshots) {
    c.snapshot_time.push_back(e.time);
    c.snapshot_count.push_back(e.count);
  }
  return c;
}
void H5Output::set_flush_seconds(double seconds) { impl_->flush_seconds = seconds; }
double H5Output::flush_seconds() const { return impl_->flush_seconds; }
bool H5Output::is_open() const { return impl_->file.valid(); }
const std::string& H5Output::path() const { return impl_->path; }
std::string H5Output::xdmf_path() const { return h5::XdmfPath(impl_->path); }
int64_t H5Output::snapshot_count() const { return static_cast<int64_t>(impl_->snapshots.size()); }
bool H5Output::swmr() const { return impl_->swmr; }

// ---------------------------------------------------------------------------------------------
// Stop signals

namespace {

volatile std::sig_atomic_t g_stop_signal = 0;

void OnStopSignal(int signal_number) {
  if (g_stop_signal != 0) {
    // Second request: the user means it. Default action (terminate) once the handler returns.
    std::signal(signal_number, SIG_DFL);
    std::raise(signal_number);
    return;
  }
  g_stop_signal = signal_number;
}

}  // namespace

void InstallStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  // Past a file size limit (ulimit -f) a write fails with EFBIG, reported as any failed write,
  // instead of the signal killing the process with the output half flushed.
  std::signal(SIGXFSZ, SIG_IGN);
}

bool StopRequested() { return g_stop_signal != 0; }
int StopSignal() { return g_stop_signal; }
void ClearStopRequest() { g_stop_signal = 0; }

}  // namespace sim

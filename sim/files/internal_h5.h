// Internal to sim/ (not a public header): RAII handles and helpers over the HDF5 C API shared by
// the run output (h5_output.cpp), the bed files (bed_io.cpp) and the reader of saved runs
// (saved_run.cpp). Writing helpers are implemented in h5_output.cpp, reading ones (OpenForReading,
// Reader) in h5_reader.cpp.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "dem/system.h"
#include "dem/vec3.h"
#include "sim/files/world_view.h"

namespace sim::h5 {

// Owns one HDF5 identifier and closes it with the matching H5xclose on destruction.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      closer_ = o.closer_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; returns the close status (0 when there was nothing to close).
  herr_t reset() {
    herr_t status = 0;
    if (id_ >= 0 && closer_ != nullptr) status = closer_(id_);
    id_ = H5I_INVALID_HID;
    return status;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// Throw std::runtime_error("HDF5: <what> failed") when an HDF5 call reports failure (< 0).
hid_t CheckId(hid_t id, const std::string& what);
void CheckOk(herr_t status, const std::string& what);

// Creates the parent folders of `path`; throws sim::InputError naming the path on failure.
void MakeParentFolders(const std::string& path);

// Creates the parent folders of `path` and the file itself (truncating), through the clean-header
// driver (below: a failed write, a full disk, leaves HDF5 able to close the file). With `swmr`,
// the file uses the 1.10 format and single-writer/multiple-reader mode, which keeps everything
// flushed readable by any reader after a SIGKILL (see H5Output); *got_swmr says whether that mode
// could be had. Turns off HDF5's printing of its error stack (every call is checked and reported
// on one line). Throws sim::InputError naming the file when it cannot be created, and
// sim::OutputError when it cannot be written (a full disk). Messages name it `name` (the output a
// temporary file will become), or `path` when that is empty.
Handle CreateFile(const std::string& path, bool swmr, bool* got_swmr, const std::string& name = "");

// Link-creation properties that create missing intermediate groups ("/series/scoop/force").
Handle IntermediateGroupsLcpl();

// Objects made while a run writes its file are made anonymous (H5Gcreate_anon, H5Dcreate_anon),
// filled, written to disk, and only then linked into the tree. HDF5 writes a new object's header
// and the parent's new link in one flush, in no set order; a kill between the two left a link to
// a header never written, which plain readers cannot follow (h5dump stops at it, h5py too when
// it is early in the tree; RunOutputTest caught one in CI). LinkWhenWritten flushes the file
// (the object's headers, its data and everything linked into it reach the disk), then links it
// at `path`: one rewrite of the parent's header (GroupGcpl), so a kill leaves either no trace of
// the object in the tree or all of it.
void LinkWhenWritten(hid_t file, hid_t object, const std::string& path);
// Makes each missing group of the absolute `path` (and `path` itself) that way, room for `links`
// links in each (GroupGcpl).
void MakeGroups(hid_t file, const std::string& path, unsigned links);
// The absolute path of the group that holds `path` ("/" for "/a").
std::string ParentOf(const std::string& path);

// Group-creation properties for a group that will hold up to `links` links. HDF5 keeps up to 8
// links in a group's object header and at the 9th moves them to "dense" storage (a fractal heap
// and a name-index B-tree). Adding a link to a dense group rewrites the B-tree's header and a node
// in two writes, and a reader needs both (their record counts must agree): a run killed between
// them leaves a group whose links HDF5's readers cannot follow (h5ls crashed on such files; the
// resume said "/snapshots/000000/id: missing"). In the header, a new link is one rewrite of it.
// So a group keeps its links in its header up to `links`, and the header is made large enough for
// them when the group is made (H5Pset_est_link_info): under SWMR, HDF5 1.10.8 fails the next flush
// when a header must grow ("slist not empty"). Past `links` the group goes dense, as HDF5's
// default does at 9. CreateFile gives the root group kGroupLinks, and HDF5 gives an intermediate
// group its parent's settings.
constexpr unsigned kGroupLinks = 64;     // an ordinary group (the most: /arm, 12 datasets)
constexpr unsigned kSnapshotLinks = 16;  // a snapshot: 9 datasets and meshes
Handle GroupGcpl(unsigned links);

// The clean-header file driver (h5_clean_driver.cpp): POSIX I/O that keeps the superblock on disk
// that of a closed file (consistency flags clear, end-of-file address covering every write), and
// drops every write after the first failed one (the file stays as it was then). Registered on
// first use.
hid_t CleanHeaderDriver();
// What the driver saw of a file it has open.
struct CleanDriverState {
  bool failed = false;     // a write failed (the file stays as it was then)
  int error = 0;           // its errno (ENOSPC, EFBIG, EIO, ...)
  uint64_t file_size = 0;  // bytes in the file [B]
};
// That of an open file of this driver, live until the file is closed; nullptr for another driver.
const CleanDriverState* CleanDriverStateOf(hid_t file);
// Runs `write` on `file` (made by CreateFile, not SWMR) and flushes it. When a write failed
// (a full disk, the file size limit), throws sim::OutputError "NAME: write failed (REASON)"
// instead of HDF5's "HDF5: H5Dwrite ... failed"; the file can then be closed and removed.
void WriteNewFile(hid_t file, const std::string& name, const std::function<void()>& write);

// Root or object attributes; an existing attribute of that name is replaced. Strings are stored
// as variable-length UTF-8.
void WriteStringAttribute(hid_t object, const std::string& name, const std::string& value);
void WriteDoubleAttribute(hid_t object, const std::string& name, double value);
void WriteU64Attribute(hid_t object, const std::string& name, uint64_t value);
// `state_hash` as 16 lower-case hex digits and `state_hash_u64` as an unsigned 64-bit integer.
void WriteStateHash(hid_t object, uint64_t hash);
std::string HexHash(uint64_t hash);
// Reads a string attribute (variable- or fixed-length); throws std::runtime_error if absent.
std::string ReadStringAttribute(hid_t object, const std::string& name);

// Writes a fixed-size array dataset `name` under `location`: (rows x width), 1-D when width == 1.
// Chunked (up to kSnapshotChunkRows rows) with shuffle + deflate level 4 when rows > 0
// (contiguous when empty: HDF5 chunks must not be empty). `file_type` is the stored type,
// `memory_type` that of `data`.
constexpr hsize_t kSnapshotChunkRows = 16384;
void WriteArray(hid_t location, const std::string& name, hid_t file_type, hid_t memory_type,
                const void* data, hsize_t rows, hsize_t width);
// Sets string attribute `attribute` of the dataset `dataset` under `location`.
void WriteDatasetAttribute(hid_t location, const std::string& dataset, const std::string& attribute,
                           const std::string& value);
// quaternion_order (and columns, for a 7-column pose) on `dataset` under `location`
// (sim::kQuaternionOrder, sim::kPoseColumns).
void MarkQuaternions(hid_t location, const std::string& dataset, bool pose);
// Writes an opaque serialised state (System::SaveState and the like) as a 1-D uint8 dataset.
void WriteBytes(hid_t location, const std::string& name, const std::vector<char>& bytes);

// Storage indices of the particles sorted by persistent id (output is always in id order).
std::vector<size_t> IdOrder(const dem::Particles& particles);

// The meshes of one role in a snapshot (/snapshots/NNNNNN/meshes/<name>), for the XDMF.
struct MeshEntry {
  std::string name;    // MeshRoleName: "scoop", "arm", "obstacles"
  int64_t points = 0;  // vertices
  int64_t triangles = 0;
};

// One particle snapshot as referenced by the XDMF sidecar.
struct SnapshotEntry {
  std::string group;  // "/snapshots/000012"
  double time = 0;    // [s]
  int64_t count = 0;  // particles
  std::vector<MeshEntry> meshes;
};
std::string SnapshotGroupName(int64_t index);

// Makes /snapshots, with room in its header for `capacity` snapshots (GroupGcpl), unless the file
// has it already.
void MakeSnapshotsGroup(hid_t file, int64_t capacity);
// The room /snapshots of `file` was made with (its estimated link count); 0 without one.
int64_t SnapshotsCapacity(hid_t file);

// Makes snapshot `index`, not yet linked (LinkWhenWritten it at the entry's group,
// /snapshots/NNNNNN, once whole): attribute time; datasets id int64 (N), position, velocity,
// angular_velocity (N x 3) [SI], radius (N), material int32 (N), speed |v| (N), connectivity
// int64 0..N-1 (N), all in persistent-id order. This is the one writer of particle arrays: the
// bed file hard-links its /particles datasets to the snapshot's.
Handle MakeParticleSnapshot(hid_t file, int64_t index, double time, const dem::Particles& particles,
                            SnapshotEntry* entry);
// MakeParticleSnapshot, then linked at its group (made first, with /snapshots if missing).
SnapshotEntry WriteParticleSnapshot(hid_t file, int64_t index, double time,
                                    const dem::Particles& particles);

// Writes the meshes of a snapshot under meshes/<name> of the snapshot's `group` (open, not yet
// linked: MakeParticleSnapshot), one group per role (in the order
// the roles first appear in `meshes`), each the role's parts together in world coordinates:
//   points (V x 3) [m], triangles int64 (T x 3) (indices into points, counter-clockwise seen from
//   outside as the part's mesh), part int32 (T) (the part, 0.., in `meshes` order), pose
//   (P x 7) (each part's body -> world pose: x y z [m], qw qx qy qz), so that a part's points
//   are its body-frame vertices moved by its pose.
// Meshes given as null are skipped. Written in the snapshot's own group
// (sim/files/snapshot_meshes.cpp).
std::vector<MeshEntry> WriteSnapshotMeshes(hid_t group, const std::vector<MeshView>& meshes);
// The XDMF3 grids of the snapshots' meshes: per mesh name a temporal collection of Triangle grids
// (geometry `points`, cell attribute `part`), written into the sidecar's domain.
std::string MeshGridsXdmf(const std::string& h5_file_name,
                          const std::vector<SnapshotEntry>& snapshots);
// %.17g: the XDMF's times.
std::string FormatDouble(double value);

// "<path without extension>.xdmf" next to the HDF5 file.
std::string XdmfPath(const std::string& h5_path);
// (Re)writes the XDMF3 sidecar of `h5_path` listing `snapshots` as a temporal collection of
// Polyvertex grids (ParaView 5.11 needs the explicit connectivity item). Written to a temporary
// file and renamed, so a reader never sees half a file. Throws std::runtime_error on I/O failure.
void WriteXdmf(const std::string& h5_path, const std::vector<SnapshotEntry>& snapshots);

// ---------------------------------------------------------------------------------------------
// Reading

// Opens `path` read-only. With `swmr_fallback`, a file HDF5 still marks as open for writing (a run
// in progress, or one that was killed: see h5_output.h) is opened the SWMR way instead. Throws
// sim::InputError "<path>: not a readable HDF5 file" when it cannot be opened either way.
Handle OpenForReading(const std::string& path, bool swmr_fallback);

// Reads the datasets and attributes of an open file, turning every problem (missing, wrong shape
// or type, unreadable) into a sim::InputError that names the file and the object:
// "out.h5: /snapshots/000003/radius: expected shape (12), got (11)". HDF5's own error stack is
// silenced around the probes.
class Reader {
 public:
  Reader(std::string path, hid_t file) : path_(std::move(path)), file_(file) {}

  const std::string& path() const { return path_; }
  hid_t file() const { return file_; }
  [[noreturn]] void Fail(const std::string& object, const std::string& message) const;

  // True if every link along the absolute `name` exists.
  bool Exists(const std::string& name) const;
  // The names of the links in group `name`, sorted; Fail when it is not a group.
  std::vector<std::string> List(const std::string& name) const;

  // Reads a numeric dataset of shape (rows) for width 1 or (rows x width) as `memory_type`, its
  // stored type being of `type_class` (H5T_FLOAT, H5T_INTEGER; H5T_NO_CLASS: either, converted
  // by HDF5, e.g. bit masks stored uint64 now and float64 by older runs). `rows` < 0 accepts any
  // row count; the count read is returned in *rows_read.
  template <typename T>
  std::vector<T> Read(const std::string& name, H5T_class_t type_class, hid_t memory_type,
                      int64_t rows, hsize_t width, int64_t* rows_read = nullptr) const {
    const Handle dataset = OpenDataset(name);
    const hsize_t n = CheckShape(name, dataset.get(), type_class, rows, width);
    std::vector<T> values(static_cast<size_t>(n * width));
    if (!values.empty()) ReadAll(name, dataset.get(), memory_type, values.data());
    if (rows_read != nullptr) *rows_read = static_cast<int64_t>(n);
    return values;
  }
  // As Read, for a series of a run's group (/scoop, /arm, /series, /bonds): the first `rows`
  // rows (the group's time's length) of a dataset that may hold more. H5Output writes a group's
  // time last in each flush, so a kill inside a flush, or a reader of a live file, can find the
  // other series longer than time, never shorter (docs/files.md, "Crash-safe output").
  template <typename T>
  std::vector<T> ReadSeries(const std::string& name, H5T_class_t type_class, hid_t memory_type,
                            int64_t rows, hsize_t width) const {
    const Handle dataset = OpenDataset(name);
    CheckShape(name, dataset.get(), type_class, rows, width, /*at_least=*/true);
    std::vector<T> values(static_cast<size_t>(rows) * width);
    if (!values.empty())
      ReadFirstRows(name, dataset.get(), memory_type, rows, width, values.data());
    return values;
  }
  // Floating-point (rows x 3) as vectors; `rows` < 0 accepts any row count. With `series`, the
  // first `rows` rows of a series that may hold more (ReadSeries).
  std::vector<dem::Vec3> ReadVectors(const std::string& name, int64_t rows,
                                     bool series = false) const;
  // A 1-D uint8 dataset written by WriteBytes, any length.
  std::vector<char> ReadBytes(const std::string& name) const;
  // A 1-D dataset of strings (variable- or fixed-length).
  std::vector<std::string> ReadStrings(const std::string& name) const;

  // Attributes of the object `object` ("/" for the root group).
  bool HasAttribute(const std::string& object, const std::string& attribute) const;
  double ReadDoubleAttribute(const std::string& object, const std::string& attribute) const;
  std::string ReadStringAttribute(const std::string& object, const std::string& attribute) const;

 private:
  Handle OpenDataset(const std::string& name) const;
  // Checks rank, extent and type class of `dataset`; returns its row count.
  // With `at_least`, more than `rows` rows pass too.
  hsize_t CheckShape(const std::string& name, hid_t dataset, H5T_class_t type_class, int64_t rows,
                     hsize_t width, bool at_least = false) const;
  void ReadAll(const std::string& name, hid_t dataset, hid_t memory_type, void* data) const;
  void ReadFirstRows(const std::string& name, hid_t dataset, hid_t memory_type, int64_t rows,
                     hsize_t width, void* data) const;
  // Opens attribute `attribute` of `object`; Fail when it is missing.
  Handle OpenAttribute(const std::string& object, const std::string& attribute) const;

  std::string path_;
  hid_t file_;
};

}  // namespace sim::h5

// The results file of a run: time series appended row by row, particle snapshots with an XDMF3
// sidecar for ParaView, and root attributes (scene, version, final state hash).
//
// File layout (HDF5, 1.10 format):
//   /                       attributes scene_yaml, version (strings); state_hash (16 hex digits)
//                           and state_hash_u64 once set; any SetAttribute() values
//   /series/...             time series: extendable (n) for width 1, (n x width) otherwise;
//                           float64, or uint64 for bit masks; chunks of 1024 rows, shuffle +
//                           deflate 4
//   /snapshots/NNNNNN       attribute time [s]; id int64 (N), position, velocity,
//                           angular_velocity (N x 3), radius (N), material int32 (N), speed (N),
//                           connectivity int64 (N) = 0..N-1; all in persistent-id order, SI units
//   /snapshots/NNNNNN/meshes/<name>   the meshes at that instant, one group per role: scoop, arm
//                           (its links but the scoop), obstacles; points (V x 3) in world
//                           coordinates [m], triangles int64 (T x 3), part int32 (T), pose
//                           (P x 7: each part's body -> world, x y z qw qx qy qz)
//                           (sim/files/internal_h5.h, WriteSnapshotMeshes)
//   /bonds/                 a bonded bed's (issue 44; docs/outputs.md "/bonds/"), written by
//                           sim::World: time, intact (n) beside /series/; broken/time (m),
//                           broken/pair uint64 (m x 2), broken/position (m x 3), broken/mode
//                           uint64 (m: 1 tension, 2 shear), broken/stress (m) [Pa]
//   <name>.xdmf             next to <name>.h5: XDMF3 temporal collection of the snapshots
//                           ("particles", Polyvertex), and one of Triangle grids per mesh name;
//                           written only when the file has snapshots
// Every time in the file (rows, snapshots, the XDMF) is on the run's one clock, the DEM state's
// (t = 0 at the start of the pour); a run's root attribute start_time is when its dig (or plain
// run) began on it (README "One clock").
//
// Crash safety (docs/files.md "Crash-safe output"): the file is written in HDF5's
// single-writer/multiple-reader (SWMR) mode, whose ordered metadata writes keep every prefix of
// the writes a consistent file, through a file driver that keeps the superblock on disk that of a
// closed file. A run killed at any moment (SIGKILL included) leaves a file that opens as any other
// (h5py, h5dump, ParaView; no h5clear) with every row up to its last Flush(). Rows reach the file
// only in Flush() (MaybeFlush: every flush_seconds or at a chunk's worth of rows; a snapshot;
// Close()),
// so a dataset's row count never runs ahead of its rows. A write that fails (disk full, file size
// limit) stops all writing: the file keeps its last flush and the error (OutputError) says which
// file, how much it holds and which rows it keeps. One writer at a time: a second H5Output on the
// same path is refused (sim::InputError). Partial chunks at the end of a series are stored
// unfiltered until they fill up (H5D_CHUNK_DONT_FILTER_PARTIAL_CHUNKS): SWMR never reuses the
// space of a rewritten chunk, and this bounds that leak to one uncompressed chunk per chunk
// instead of one per flush.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dem/system.h"
#include "sim/files/world_view.h"

namespace sim {

// The quaternion order of every dataset that holds quaternions (/scoop/pose, the snapshots' mesh
// poses, a bed's /clumps/orientation), stated at it as the string attribute quaternion_order:
// scalar first, w x y z (ROS's geometry_msgs/Quaternion puts w last). A pose of 7 columns also
// names them (attribute columns).
constexpr const char* kQuaternionOrder = "w x y z";
constexpr const char* kPoseColumns = "x y z qw qx qy qz";

// A write of the output failed; what() is the one line to print (file, size, rows kept).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Where an output stands after a flush: the rows of each series and the snapshots (a run's
// checkpoint keeps it; a resumed run's output is made again up to it).
struct OutputCursor {
  std::vector<std::pair<std::string, int64_t>> rows;  // dataset path, rows
  std::vector<double> snapshot_time;                  // [s], one per snapshot
  std::vector<int64_t> snapshot_count;                // particles of each
};

class H5Output {
 public:
  // Creates (truncates) `path` and its parent folders and writes the root attributes. With
  // `resume`, the new file first takes from the file now at `path` the rows and snapshots the
  // cursor names (InputError when that file holds fewer). Throws sim::InputError naming the path
  // when the file cannot be created or another process writes it (the lock is held until
  // Close()).
  H5Output(const std::string& path, const std::string& scene_yaml, const std::string& version,
           double flush_seconds = 10.0, const OutputCursor* resume = nullptr);
  ~H5Output();  // Close(); errors are swallowed (call Close() to see them)
  H5Output(const H5Output&) = delete;
  H5Output& operator=(const H5Output&) = delete;

  // Appends one row of `width` values to the time series `dataset` ("/series/time"; groups are
  // created as needed). Rows are buffered and written a chunk at a time. The width of a dataset
  // is fixed by its first row (std::invalid_argument on a mismatch).
  void AppendRow(const std::string& dataset, const double* values, int width);
  // The same for bit masks: the dataset is uint64 (a dataset keeps the type of its first row).
  void AppendRow(const std::string& dataset, const uint64_t* values, int width);
  // A string attribute of the series `dataset` (e.g. quaternion_order), written when it is made:
  // call it before the dataset's first row (in SWMR mode an attribute added to a dataset that
  // holds rows can find no room in its header). A resumed output takes them from the old file.
  void SetSeriesAttribute(const std::string& dataset, const std::string& name,
                          const std::string& value);

  // Writes `dataset` once as a one-dimensional table of `rows` records (HDF5 compound; zero rows
  // allowed), one field per column, in the columns' order.
  struct TableColumn {
    enum class Kind { kFloat64, kUint64, kInt32, kText };
    std::string name;
    Kind kind = Kind::kFloat64;
    std::vector<double> float64;  // the rows of the one that `kind` names
    std::vector<uint64_t> uint64;
    std::vector<int32_t> int32;
    std::vector<std::string> text;  // stored fixed-length, NUL-terminated
  };
  void WriteTable(const std::string& dataset, const std::vector<TableColumn>& columns,
                  int64_t rows);

  // Writes /snapshots/NNNNNN (sequential from 000000) with `meshes` (the scoop, the arm's links,
  // the obstacles at that instant), flushes the file, then rewrites the XDMF sidecar, so the
  // sidecar only names data that is on disk.
  void WriteSnapshot(double time, const dem::Particles& particles,
                     const std::vector<MeshView>& meshes = {});

  // How many snapshots the run plans: /snapshots is made, at the first, with room for them (and
  // a quarter more) in its header, where a SIGKILL cannot tear its list (sim/files/internal_h5.h,
  // GroupGcpl). Without a plan: room for kDefaultSnapshotCapacity. Past the room, snapshots are
  // still written.
  void PlanSnapshots(int64_t count);
  static constexpr int64_t kDefaultSnapshotCapacity = 1024;

  void SetStateHash(uint64_t hash);  // root state_hash (hex string) and state_hash_u64
  void SetAttribute(const std::string& name, double value);
  void SetAttribute(const std::string& name, const std::string& value);
  void SetCountAttribute(const std::string& name, uint64_t value);  // counts and bit sets: uint64

  // Puts what follows under `group` (a study writes one dig per group): AppendRow("/scoop/time")
  // then writes <group>/scoop/time, and SetAttribute / SetStateHash set attributes of the group
  // (created as needed) instead of the root. "" returns to the root. Snapshots stay at the root.
  void SetGroup(const std::string& group);

  // Flush() if at least flush_seconds of wall time have passed since the last flush or a series
  // holds a chunk's worth of rows; returns whether it flushed. Cheap enough to call every step;
  // call it between steps (rows appended since reach the file only in a flush).
  bool MaybeFlush();
  // Writes the buffered rows and flushes the file to disk.
  void Flush();
  // Writes everything and closes the file; idempotent. After it the file is complete. After a
  // failed write it only closes (throws nothing more).
  void Close();
  // A write failed (OutputError was thrown): nothing more is written.
  bool failed() const;
  // Flush()es and says where the file stands.
  OutputCursor Cursor();

  void set_flush_seconds(double seconds);
  double flush_seconds() const;
  bool is_open() const;
  const std::string& path() const;
  std::string xdmf_path() const;
  int64_t snapshot_count() const;
  // False when the file system refused SWMR mode and the file was created without it (still
  // flushed, but then a SIGKILL can leave metadata half written).
  bool swmr() const;

 private:
  template <typename T>
  void Append(const std::string& dataset, const T* values, int width);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Every output file (a run's, a bed, a study's, a sweep's case file and table, the wrench table
// and its CSV) is refused where an output cannot go, before any work and again when it is put in
// place: a path that exists and is not a regular file (a device, a FIFO, a folder: writing
// would replace it), or a file another process writes. The writers share one lock: an
// open-file-description write lock (fcntl F_OFD_SETLK) on the file at the path, which H5Output
// holds from its constructor to Close() and a file put in place by PlaceOutput only while it
// replaces the old one.
// Throws sim::InputError naming `path` when it cannot be an output.
void CheckOutputPath(const std::string& path);
// Puts the file `temporary` (written and closed) in place at `path` with rename(), refused as
// CheckOutputPath (sim::InputError); on any failure `temporary` is removed.
void PlaceOutput(const std::string& temporary, const std::string& path);

// Graceful stop on SIGINT/SIGTERM: the handler only sets a flag (volatile sig_atomic_t); the run
// loop polls StopRequested(), closes its output and exits. A second signal of either kind
// terminates the process at once (default action). SIGXFSZ is ignored: a write past the file
// size limit fails (EFBIG) and is reported as any failed write.
void InstallStopHandlers();
bool StopRequested();
int StopSignal();         // the signal that asked to stop (SIGINT, SIGTERM), 0 if none
void ClearStopRequest();  // forget a request (tests; a run that handled it and goes on)

}  // namespace sim

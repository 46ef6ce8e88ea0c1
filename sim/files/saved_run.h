// The one reader of a saved run: an OUT.h5 written by sim::H5Output (layout in
// sim/files/h5_output.h), read back for `scoopsim render` and anyone else who wants a run's stored
// scene, its particle snapshots or its scoop's series. Public header; the HDF5 C API stays inside
// sim/.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dem/system.h"
#include "dem/transform.h"
#include "dem/vec3.h"
#include "sim/input/scene.h"

namespace sim {

// One particle snapshot of a run (/snapshots/NNNNNN).
struct SnapshotInfo {
  std::string group;  // "/snapshots/000012"
  double time = 0;    // [s] (the group's attribute time)
};

// The scoop's series of a dig (/scoop/...), one row per sample, all of equal length. Fields the
// file lacks are empty.
struct ScoopSeries {
  std::vector<double> time;             // [s] (n), ascending
  std::vector<int> pass;                // dig pass, 1-based (n)
  std::vector<double> rho;              // distance along the trench since first contact [m] (n)
  std::vector<dem::Vec3> force_world;   // force on the scoop, world frame [N] (n)
  std::vector<dem::Vec3> torque_world;  // torque about the scoop CoM, world frame [N m] (n)
  std::vector<dem::Pose> pose;          // l_scoop -> world (n; stored as x y z qw qx qy qz)

  bool empty() const { return time.empty(); }
  // The last sample at or before `t` (1e-9 s slack for rounding); -1 when there is none.
  int SampleAt(double t) const;
};

// The last sample of `time` (ascending) at or before `t` (1e-9 s slack for rounding); -1 when
// there is none.
int SampleAt(const std::vector<double>& time, double t);

// The arm's series of a coupled dig (/arm/...), one row per /scoop/ row.
struct ArmSeries {
  std::vector<std::string> joints;      // root attribute arm_joints, base to tip
  std::vector<double> time;             // [s] (n)
  std::vector<double> torque_demanded;  // [N m] (n x joints, row-major)
  // The limit the arm saturated at, derated [N m] (n x joints): /arm/effort_limit (the URDF's)
  // x /arm/effort_derate, or, in files older than the derate's dataset, /arm/effort_limit alone
  // (which held the derated limit then).
  std::vector<double> effort_limit;
  std::vector<uint64_t> fault_latched;  // every flag raised so far (n)

  bool empty() const { return time.empty() || joints.empty(); }
};

// The bonds of a bonded run (/bonds/..., issue 44): the intact count over time and the bonds
// that broke, one record each, in the order they broke. Empty for an unbonded run.
struct BondSeries {
  std::vector<double> time;    // [s] (n): the rows of /series/ (plain run) or /scoop/ (dig)
  std::vector<double> intact;  // intact bonds then (n)
  // The broken bonds (m records): end of the step each broke in [s], the two spheres'
  // persistent ids (a < b), the contact point then [m], the mode (1 tension, 2 shear,
  // dem::BondBreakMode) and the stress that broke it (sigma or tau) [Pa].
  std::vector<double> broken_time;
  std::vector<int64_t> broken_a, broken_b;
  std::vector<dem::Vec3> broken_position;
  std::vector<int> broken_mode;
  std::vector<double> broken_stress;

  bool empty() const { return time.empty() && broken_time.empty(); }
};

// How many broken bonds each particle has: counts[i] = the records k with a[k] or b[k] equal to
// ids[i] (any order of ids; an id named by no record counts 0, a record's id not among ids is
// skipped). As floats, for a colour field.
std::vector<float> BrokenBondCounts(const std::vector<int64_t>& ids, const std::vector<int64_t>& a,
                                    const std::vector<int64_t>& b);

// A mesh stored with a snapshot (/snapshots/NNNNNN/meshes/<name>, sim/files/h5_output.h): the parts
// of one role together, in world coordinates.
struct SnapshotMesh {
  std::string name;        // "scoop", "arm", "obstacles"
  dem::TriangleMesh mesh;  // world coordinates [m]
};

class SavedRun {
 public:
  // Opens `h5_path` read-only; a run still marked open for writing (in progress, or killed) is
  // opened the SWMR way. Throws InputError naming the path when it is not a readable HDF5 file.
  explicit SavedRun(const std::string& h5_path);
  ~SavedRun();
  SavedRun(const SavedRun&) = delete;
  SavedRun& operator=(const SavedRun&) = delete;

  const std::string& path() const;

  // A string attribute of the root group (scene_yaml, version, state_hash, scoop_mesh, ...); ""
  // when the file has none. Throws InputError when it is there but not a string.
  std::string RootAttribute(const std::string& name) const;
  // The scene text the run was made from (root attribute scene_yaml); "" when it has none.
  std::string SceneYaml() const;
  // Its box, gravity and `render:` block (sim::ParseStoredScene; messages name
  // "<path>:scene_yaml"). Throws InputError for a stored text LoadScene would have refused there.
  StoredScene Scene() const;

  // The snapshots in order. Throws InputError naming the path when the file holds none (a run
  // with output.snapshot_every = 0).
  std::vector<SnapshotInfo> Snapshots() const;
  // Reads the particles of `snapshot` into `*particles` (id, x, v, w, radius, material; other
  // fields left empty), in persistent-id order. Throws InputError naming the path and dataset
  // for a missing dataset or one of the wrong shape.
  void ReadSnapshot(const SnapshotInfo& snapshot, dem::Particles* particles) const;

  // The /scoop/ series (time, pass, rho, force_world, torque_world, pose); empty when the run had
  // no dig. Throws InputError for a series whose length differs from /scoop/time's.
  ScoopSeries Scoop() const;
  // The /arm/ series; empty when the run had no arm. InputError for a series of the wrong shape.
  ArmSeries Arm() const;
  // The /bonds/ series and broken-bond records; empty for an unbonded run. InputError for a
  // series or a record field whose length differs from its time's.
  BondSeries Bonds() const;
  // The meshes stored with `snapshot` (none for a run without a dig, or written before them).
  // InputError for a mesh group of the wrong shape.
  std::vector<SnapshotMesh> ReadSnapshotMeshes(const SnapshotInfo& snapshot) const;
  // A numeric root attribute (start_time, surface, ...); `fallback` when the file has none.
  double RootNumber(const std::string& name, double fallback) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim

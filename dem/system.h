// The DEM world: a const model (materials, walls, step size) and a mutable particle state, advanced
// by Step(). Public header of the dem module; everything in dem/internal_*.h is private to dem/.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "dem/bond.h"
#include "dem/clump.h"
#include "dem/material.h"
#include "dem/mesh.h"
#include "dem/thread_governor.h"
#include "dem/vec3.h"

namespace dem {

namespace internal {
struct Workspace;  // the step's working data (dem/internal_workspace.h, private to dem/)
}

// An infinite plane wall: particles live on the side the normal points to.
struct Plane {
  std::string name;
  Vec3 point;   // a point on the plane [m]
  Vec3 normal;  // unit normal into the particle side [-]
  int material = 0;
};

// Sleeping: particles at rest far from every mesh are frozen (not integrated; no contact between
// two sleeping particles is computed, though a sleeping particle still pushes on awake ones) and
// wake when a mesh comes near or a moving particle touches them. Decisions are taken every
// `check_every` steps from the data alone, so runs stay deterministic.
struct SleepConfig {
  bool enabled = false;
  // Thresholds measured on scenes/sleep_check.yaml: a quiet speed of 2e-3 m/s raised the mean
  // |F| of a dig by 6%, 5e-4 m/s by 0.9% (bench/sleep_accuracy.sh; docs/dem.md).
  double speed = 5e-4;          // a particle is quiet below this speed (and spin * radius) [m/s]
  double wake_speed = 1e-3;     // a sleeping particle touched by one faster than this wakes [m/s]
  double wake_distance = 0.01;  // particles whose centre is this close to a mesh stay awake [m]
  double wake_margin = 0.005;   // when a sleeper enters that zone, every sleeper within
                                // wake_distance + wake_margin wakes at once, so wake-ups come
                                // once per wake_margin of travel [m]
  int check_every = 50;         // steps between sleep/wake checks
  int quiet_checks = 5;         // consecutive quiet checks before a particle falls asleep
};

struct SystemConfig {
  Vec3 gravity{0, 0, -9.81};  // [m/s^2]
  double time_step = 0;       // [s]
  double skin = 0;            // Verlet-list skin [m]; the list is rebuilt when a particle has
                              // moved more than skin/2 since the last build
  // The force pass scans only the list pairs closer than near_fraction * skin (gap between the
  // surfaces), made again when some particle may have moved half that. A pure saving: any value
  // > 0 gives bit-identical results (a larger one, the whole list).
  double near_fraction = 0.1;
  // With sleeping, a neighbour-list build makes again only the slabs of the cell grid where
  // particles moved since the last build, when the grid stays the same (dem/neighbor_build.cpp,
  // RebuildPart). A pure saving: bit-identical results either way; false builds it all.
  bool partial_rebuild = true;
  Vec3 domain_min, domain_max;  // box that holds every particle; sets the cell grid [m]
  std::vector<Plane> planes;
  // Health limits (Step() reports, the caller decides to stop).
  double max_speed = 100.0;            // runaway speed [m/s]; knob: time step, restitution
  double max_overlap_fraction = 0.05;  // overlap / smaller diameter; knob: time step, stiffness
  SleepConfig sleep;
  // The rolling-friction couples of particle-mesh contacts count in the mesh's torque (EDEM
  // leaves them out by default, and so does this).
  bool mesh_rolling_torque = false;
};

// Persistent state of one contact, keyed by the persistent ids of its two sides. `b` is a particle
// id, or -1 - k for plane k. `shear` is the Mindlin tangential spring displacement [m] as seen by
// a.
struct ContactRecord {
  int64_t a = 0;
  int64_t b = 0;
  Vec3 shear;
};

// Health of a step (STYLE.md habit 8). Flags are a bit mask; `particle` and `time` locate the first
// offence and `message` says what happened and which knob to turn.
enum StepFlag : uint32_t {
  kStepOk = 0,
  kNonFinite = 1u << 0,         // NaN/inf in a position or velocity: lower time_step
  kExcessiveOverlap = 1u << 1,  // overlap above max_overlap_fraction: lower time_step or raise G
  kRunawaySpeed = 1u << 2,      // speed above max_speed: lower time_step, check restitution <= 1
  kLeftDomain = 1u << 3,        // particle outside domain_min..domain_max: add walls or enlarge
};
struct StepStatus {
  uint32_t flags = kStepOk;
  int64_t particle = -1;  // persistent id of the first offending particle
  double time = 0;        // simulated time of the offence [s]
  std::string message;
  bool ok() const { return flags == kStepOk; }
};

// Per-particle state, one contiguous array per field, in storage order. Storage order changes when
// the neighbour list reorders particles for locality; `id` is the persistent identity.
struct Particles {
  std::vector<int64_t> id;          // persistent id (N)
  std::vector<Vec3> x;              // centre [m] (N)
  std::vector<Vec3> v;              // velocity [m/s] (N)
  std::vector<Vec3> w;              // angular velocity [rad/s] (N)
  std::vector<Vec3> f;              // force of the last step [N] (N)
  std::vector<Vec3> t;              // torque of the last step [N m] (N)
  std::vector<double> radius;       // [m] (N)
  std::vector<double> mass;         // [kg] (N)
  std::vector<double> inv_mass;     // [1/kg] (N)
  std::vector<double> inv_inertia;  // 1 / (2/5 m r^2) [1/(kg m^2)] (N)
  std::vector<int32_t> material;    // index into the MaterialTable (N)
  std::vector<uint8_t> awake;       // 1 = integrated, 0 = sleeping (SleepConfig) (N)
  size_t size() const { return id.size(); }
};

struct NeighborStats {
  int64_t builds = 0;          // neighbour-list builds so far
  int64_t partial_builds = 0;  // of those, builds of a part (SystemConfig::partial_rebuild) since
                               // the System was made or restored
  int64_t near_builds = 0;     // near-list builds so far (SystemConfig::near_fraction)
  int64_t near_pairs = 0;      // near pairs at the last near-list build
  int64_t pairs = 0;           // half-list pairs (within cutoff + skin) at the last build
  int64_t contacts = 0;        // particle-particle pairs in contact after the last step
  int64_t wall_contacts = 0;   // particle-plane contacts after the last step
  int64_t mesh_contacts = 0;   // particle-mesh contacts after the last step (after deduplication)
  int64_t awake = 0;           // particles awake (integrated) at the last step
  double max_overlap = 0;      // deepest overlap at the last step: particle-particle, -plane or
                               // -mesh, / the smaller diameter [-]
};

// Wall-clock seconds spent in each part of Step() since the system was made: the breakdown a
// LIGGGHTS run prints at its end (Pair, Neigh, Modify...), for finding where a run's time goes.
struct PhaseTimes {
  double integrate = 0;  // the two half kicks, the drift test and the clumps' moves
  double rebuild = 0;    // neighbour-list builds (and the storage reorder that goes with them)
  double near = 0;       // near-list, busy-list and plane-visit builds
  double pairs = 0;      // particle-particle and particle-plane forces (on 2+ threads with
                         // Step()'s `motion` beside them)
  double mesh = 0;       // particle-mesh forces (with the mesh's candidate lists)
  double sleep = 0;      // sleep and wake checks, and the list of awake particles
  double bonds = 0;      // the bonds' forces (dem/bond.h) and the index of their spheres
  double Total() const { return integrate + rebuild + near + pairs + mesh + sleep + bonds; }
};

// Wrench of the particles on a mesh during the last step, world frame.
struct MeshWrench {
  Vec3 force;   // sum of the contact forces on the mesh [N]
  Vec3 torque;  // sum of (contact point - body origin) x force [N m] (+ the rolling couples with
                // SystemConfig::mesh_rolling_torque), about the mesh body origin
                // (MeshMotion::pose.position) at the last step
  int64_t contacts = 0;
};

class System {
 public:
  System(MaterialTable materials, SystemConfig config);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  void Reserve(size_t n);
  // Adds a sphere; returns its persistent id. Mass and inertia come from the material density.
  int64_t AddParticle(const Vec3& x, const Vec3& v, const Vec3& w, double radius, int material);
  // Removes the particles whose persistent ids are listed (with their contacts).
  // A clump goes as a whole: naming one of its spheres removes all of them.
  void RemoveParticles(const std::vector<int64_t>& ids);

  // Advances one time step (velocity Verlet). Never throws; reports its health.
  // `motion`, when given, is called once during the step, before anything reads a mesh's pose, to
  // set the meshes' motion for this step (SetMeshMotion, and nothing else of this System): a
  // coupled rigid-body step (the arm) then runs on one of the step's threads while the others
  // compute the pair forces, instead of before the step. It must not throw. On one thread it runs
  // in series and its time is not counted in any phase (PhaseTimes).
  StepStatus Step(const std::function<void()>& motion = {});

  const MaterialTable& materials() const { return materials_; }
  const SystemConfig& config() const { return config_; }
  const Particles& particles() const { return p_; }
  Particles& mutable_particles() { return p_; }  // positions/velocities only; call Touch() after
  void Touch();  // forces a neighbour-list rebuild before the next step, with the config's skin
  // Rebuilds now: storage order and neighbour list become a function of positions and ids alone.
  // Call before saving and after loading a state, so that a restored run replays bit for bit.
  void Canonicalize() { Rebuild(); }
  double time() const { return time_; }
  void set_time(double t) { time_ = t; }
  int64_t step_count() const { return step_count_; }
  NeighborStats neighbor_stats() const;
  const PhaseTimes& phase_times() const { return phase_times_; }
  // Force exerted by the particles on plane k during the last step [N].
  Vec3 plane_force(int k) const { return plane_force_[k]; }

  // Triangle-mesh walls moved kinematically (the scoop). Contacts use the Hertz-Mindlin law with
  // the (particle material, mesh material) interaction and keep tangential history per contact.
  int AddMesh(TriangleMesh mesh);  // returns the mesh index
  int num_meshes() const;
  const TriangleMesh& mesh(int k) const;
  // Pose and twist of mesh k at the end of the coming step (time() + time_step), when Step()
  // evaluates the forces. Call before every Step() while the mesh moves, or from Step()'s
  // `motion`.
  void SetMeshMotion(int k, const MeshMotion& motion);
  const MeshMotion& mesh_motion(int k) const;
  MeshWrench mesh_wrench(int k) const;

  // Rigid clumps of spheres (dem/clump.h). A template is prepared once (mass properties,
  // principal axes); a clump adds one particle per template sphere and moves them as one body.
  int AddClumpTemplate(const ClumpTemplate& t);  // returns its index (an identical one is reused)
  int num_clump_templates() const;
  const ClumpShape& clump_shape(int k) const;
  // Adds a clump of template `shape` with its template frame at `pose` (the centre of mass lands
  // at Apply(pose, clump_shape(shape).center_of_mass)), CoM velocity v and angular velocity w
  // (world); returns its index in clumps() (indices close up when a clump is removed).
  int64_t AddClump(int shape, const Pose& pose, const Vec3& v, const Vec3& w, int material);
  const Clumps& clumps() const;
  Clumps& mutable_clumps();    // to restore a saved state; the spheres are not moved
  int64_t num_bodies() const;  // single spheres + clumps

  // Breakable bonds between spheres (dem/bond.h), computed every step after the contacts, in
  // parallel with them. AddBonds throws std::invalid_argument naming the first bond whose ids are
  // unknown, equal or not in order (a < b), belong to one clump, or are bonded already (one
  // record a pair, intact or broken), or whose values are out of range (radius, kn, ks,
  // strengths <= 0 or NaN, tan_friction or damping_ratio < 0); nothing is added then. A bond with
  // a zero `normal` takes it from the spheres' positions (which must differ). A broken bond stays
  // in bonds() (intact = false) and never acts again. Removing a particle removes its bonds.
  // With sleeping, a bond between two sleepers is frozen; an awake end faster than
  // sleep.wake_speed wakes the other end, a break wakes both.
  void AddBonds(const std::vector<Bond>& bonds);
  // In the order added, with their states as of the last step (the step works on a copy in
  // storage order and brings the records up to date here: take the reference afresh after a step).
  const std::vector<Bond>& bonds() const;
  // How many bonds were added, intact or broken (cheap: bonds() first copies the step's state
  // back into the record, which a per-step check should not pay for).
  int64_t bond_count() const;
  int64_t intact_bond_count() const;
  // The bonds broken since the last call, in the order they broke (within a step, bond order).
  std::vector<BondBreak> TakeBondBreaks();
  // Pairs of spheres (persistent ids, a < b, sorted) whose surfaces are closer than `gap` [m]
  // (overlapping pairs included), not of one clump: where bonds may be made. A cell search over
  // the present positions (any gap >= 0; throws std::invalid_argument on a negative or NaN one).
  std::vector<std::pair<int64_t, int64_t>> PairsWithinGap(double gap) const;
  // The intact bonds' elastic energy (BondEnergy, dem/bond.h), summed in bond order [J].
  double BondEnergy() const;

  // Sleeping (SleepConfig); may be switched on and off between steps.
  void set_sleep(const SleepConfig& sleep);
  int64_t awake_count() const;

  // Contact history, for saving and restoring a bed bit for bit.
  std::vector<ContactRecord> Contacts() const;

  // The whole mutable state as bytes (dem/state_io.cpp): particles in storage order, clumps and
  // their templates, the neighbour, near and wall lists with the contact history they carry, the
  // meshes' motion, candidates and history, sleeping, time and counters; everything but the
  // model (materials, config, mesh geometry) and the phase clocks. A System made with the same
  // materials, config and meshes (added in the same order) that RestoreState()s them steps on
  // bit for bit as this one would, on any thread count. RestoreState throws std::runtime_error
  // when the bytes do not fit (another format, other meshes).
  std::vector<char> SaveState() const;
  void RestoreState(const std::vector<char>& bytes);
  void SetContacts(const std::vector<ContactRecord>& contacts);

  // Totals over all particles, summed in persistent-id order (a clump counts as one rigid body,
  // after the single spheres, in clump order).
  double KineticEnergy() const;    // translational + rotational [J]
  double PotentialEnergy() const;  // -m g . x [J]
  double ElasticEnergy() const;    // normal Hertz energy 2/5 k delta^(5/2) of current contacts [J]
  Vec3 Momentum() const;           // [kg m/s]
  // FNV-1a 64 hash of (id, x, v, w, radius, material) in persistent-id order, of the clumps'
  // (x, v, q, L) and of the time; with bonds, then of each bond's (a, b, intact, fn, fs, mt, mb)
  // in bond order (without any, the hash is what it was before bonds existed).
  uint64_t StateHash() const;

  // Worker threads (the most a step uses). With adaptive threads a ThreadGovernor picks each
  // step's count, from 1 to num_threads(), by timing steps (dem/thread_governor.h): another
  // process holding a core then costs a run little. Results are the same either way.
  void set_num_threads(int n);
  int num_threads() const { return num_threads_; }
  void set_adaptive_threads(bool on, const GovernorConfig& config = GovernorConfig());
  const ThreadGovernor* governor() const { return governor_.get(); }  // null when fixed

 private:
  // Reorders storage and rebuilds the lists (internal::Rebuild, dem/neighbor_build.cpp) on nt
  // threads.
  void Rebuild(int nt);
  void Rebuild() { Rebuild(num_threads_); }
  // Lists the mutable state to a dem/archive.h archive (SaveState, RestoreState).
  template <typename Archive>
  void StateFields(Archive& archive);

  MaterialTable materials_;
  SystemConfig config_;
  Particles p_;
  ClumpSet clumps_;
  std::vector<Vec3> plane_force_;
  double time_ = 0;
  int64_t step_count_ = 0;
  PhaseTimes phase_times_;
  int64_t next_id_ = 0;
  int64_t builds_ = 0;
  int num_threads_ = 1;
  std::unique_ptr<ThreadGovernor> governor_;  // adaptive threads, else null
  GovernorConfig governor_config_;
  // Everything else the step keeps between calls; its phases are plain functions over it
  // (dem/internal_phases.h).
  std::unique_ptr<internal::Workspace> ws_;
};

}  // namespace dem

// Private to dem/: nothing outside dem/ includes this header. The System's working data (what the
// step keeps between calls besides the public Particles): contact constants, the neighbour and
// near lists with the contact history they carry, the wall and mesh contacts, the sleeping
// lists, the per-thread scratch of the force pass and what is stale. The phases of the step
// (dem/internal_phases.h) are plain functions over this struct.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "dem/bond.h"
#include "dem/contact.h"
#include "dem/mesh.h"
#include "dem/neighbor.h"
#include "dem/system.h"

namespace dem::internal {

// Wall-clock seconds, for PhaseTimes.
inline double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// What must be made again before the step may use it. Whatever invalidates a thing sets its flag;
// the one function that makes it again clears it (named per flag). A fresh System has everything
// stale but the list's history, since there is no list yet.
struct Stale {
  // The neighbour list must be built before the next force pass: particles were added or
  // removed, Touch() was called, sleeping was switched, or the list's indices are stale
  // (`list`). Cleared by Rebuild.
  bool rebuild = true;
  // The list's indices no longer name the stored particles (particles removed, contact history
  // replaced), so nothing may read the list or carry its history over. Implies `rebuild`.
  // Cleared by Rebuild.
  bool list = true;
  // The list's own history arrays (Workspace::shear, touching) may lag behind the near slots',
  // which the force pass reads and writes in their place: whatever reads them calls FlushNear
  // first. Set by BuildNear; cleared by Rebuild, which flushes and then drops the near list.
  bool list_history = false;
  // The awake particles (Workspace::active): a particle woke or fell asleep, or was added or
  // removed. Cleared by RefreshActive.
  bool active = true;
  // The particles the force pass visits with sleeping on (Workspace::busy). Cleared by
  // RefreshBusy, which marks the near list and the plane visits stale in turn.
  bool busy = true;
  // The near list (Workspace::near_k ...): made at a rebuild or a busy-list change, or when some
  // particle may have moved near_skin / 2 since it was made. Cleared by BuildNear.
  bool near = true;
  // The visited particles with plane candidates (Workspace::wall_visit). Cleared by
  // ListWallVisits.
  bool walls = true;
  // Every particle's 1/|w| (Workspace::inv_spin): storage reordered or resized. Else only the
  // awake particles' change (a sleeper's spin is zero, and so is its entry). Cleared by
  // UpdateInvSpins.
  bool spins = true;
};

// Every particle alike: one radius, mass and moment of inertia (the common, monodisperse bed;
// noted at Rebuild). The force pass then reads none of them per partner: a scattered load less
// per near pair and three per contact, on a bed whose arrays do not fit in the cache.
struct Alike {
  bool all = false;  // every particle has the values below (as of the last Rebuild)
  double radius = 0, mass = 0, inv_mass = 0, inv_inertia = 0;  // [m], [kg], [1/kg], [1/(kg m^2)]
};

// Contacts gathered before one vectorised force evaluation (the touching pairs among a run of
// near slots; a batch may end inside one particle's pairs).
constexpr int kBatchContacts = 64;  // 46 arrays x 64 x 8 B = 23 KB: stays in L1

// Per-thread scratch of the force pass: the particle-pair contacts of a run of near slots,
// gathered so their forces can be computed in one vectorised loop (structure of arrays). Fixed
// arrays in one block: every column sits at a constant offset from one base register.
struct alignas(64) ContactBatch {
  static constexpr int K = kBatchContacts;
  // Inputs, gathered by the scalar pass (structure of arrays, one entry per touching pair).
  double dx[K], dy[K], dz[K];     // x_j - x_i [m]
  double dvx[K], dvy[K], dvz[K];  // v_j - v_i [m/s]
  double ax[K], ay[K], az[K];     // r_i w_i + r_j w_j [m/s] (the kernel makes it from own spins)
  double wx[K], wy[K], wz[K];     // w_i - w_j, or w_i when the pass takes own spins [rad/s]
  double wjx[K], wjy[K], wjz[K];  // w_j when the pass takes own spins (edem rolling) [rad/s]
  double ki[K], kj[K];            // 1/|w_i|, 1/|w_j| (0 at rest) with own spins [s/rad]
  double ri[K], rj[K];            // radii [m]
  double inv_m_star[K];           // 1/m_i + 1/m_j [1/kg]
  double inv_inertia[K];          // 1/I_i + 1/I_j [1/(kg m^2)]
  double e_star[K], g_star[K], damp[K], tangential_ratio[K], friction[K], rolling[K];
  double rolling_model[K];     // the pair's RollingModel, as a number (mixed batches only)
  double sx[K], sy[K], sz[K];  // tangential history in, then out [m]
  // Outputs.
  double fx[K], fy[K], fz[K];     // force on i [N]
  double tix[K], tiy[K], tiz[K];  // torque on i [N m]
  double tjx[K], tjy[K], tjz[K];  // torque on j [N m]
  double overlap[K];              // delta / smaller diameter
  int32_t i[K], j[K], k[K];       // owner, partner, near slot
  int32_t pair[K];                // index of the material pair
  uint8_t was[K];                 // the pair touched at the last step
};

// Stored tangential history of one particle-mesh contact.
struct MeshHistory {
  int32_t index;  // particle storage index
  int64_t id;     // particle persistent id
  Vec3 normal;    // contact normal (particle -> mesh) when the history was stored
  Vec3 shear;     // tangential history [m]
};

// One triangle-mesh wall and its contacts (dem/mesh_contact.cpp).
struct MeshState {
  TriangleMesh mesh;
  MeshMotion motion;
  std::vector<PairConstants> constants;  // per particle material (nm)
  std::vector<Vec3> world;               // vertices in world at `motion` [m] (V)
  double reach = 0;                      // largest vertex distance from the body origin [m]
  // Candidates: (particle, triangle) pairs within r + skin at the last candidate build, grouped
  // by particle in storage order: group g is particle group_particle[g], triangles
  // cand_tri[group_start[g] .. group_start[g + 1]].
  std::vector<int32_t> group_particle, group_start, cand_tri;
  bool candidates_valid = false;
  Pose pose_build;                   // mesh pose at the candidate build
  double particle_drift = 0;         // bound on particle displacement since the candidate build [m]
  std::vector<MeshHistory> history;  // sorted by particle storage index
  // Per-group results of the parallel pass, summed serially in group order.
  std::vector<Vec3> group_force, group_torque, group_mesh_torque;
  std::vector<double> group_overlap;              // deepest overlap / diameter of each group
  std::vector<int32_t> group_history, group_new;  // history range start; new contacts count
  std::vector<MeshHistory> fresh;                 // new history, up to 4 slots per group
  MeshWrench wrench;
};

// The force pass's per-thread runs of slabs (ComputeForces): run r hands out the positions next,
// next + 1, ... below end, to its own thread first and then to any thread that finished its own.
// Scratch, not state: a copy starts empty.
class SlabRuns {
 public:
  struct alignas(64) Run {  // one cache line each: a thread's claims do not slow another's
    std::atomic<int32_t> next{0};
    int32_t end = 0;
  };
  SlabRuns() = default;
  SlabRuns(const SlabRuns&) {}
  SlabRuns& operator=(const SlabRuns&) { return *this; }
  Run* Get(int n) {  // at least n runs
    if (n > size_) {
      runs_ = std::make_unique<Run[]>(n);
      size_ = n;
    }
    return runs_.get();
  }

 private:
  std::unique_ptr<Run[]> runs_;
  int size_ = 0;
};

// A live bond's constants, made by IndexBonds (the pass would otherwise make them every step).
struct BondConstants {
  double kn_area = 0, ks_area = 0;                  // k_n A, k_s A [N/m]
  double ks_polar = 0, kn_inertia = 0;              // k_s J, k_n I [N m/rad]
  double inv_area = 0;                              // 1 / A [1/m^2]
  double rim_over_inertia = 0, rim_over_polar = 0;  // R / I, R / J [1/m^3]
  double damp_n = 0, damp_s = 0;                    // 2 z sqrt(k_n A m*), 2 z sqrt(k_s A m*) [kg/s]
  double damp_t = 0, damp_b = 0;  // 2 z sqrt(k_s J I*), 2 z sqrt(k_n I I*) [kg m^2/s]
};

// Breakable bonds (dem/bond.h; the phase: BondForces, dem/bond.cpp). The bonds themselves, in the
// order added, are the state; the rest is made again from them and the storage order (IndexBonds)
// whenever `stale`. Arrays marked (live) have one entry per intact bond.
struct BondWork {
  std::vector<Bond> bonds;        // every bond, intact or broken (System::bonds())
  std::vector<BondBreak> breaks;  // broken since the last System::TakeBondBreaks
  // Storage order changed, particles or bonds were added or removed, or a bond broke: live, ia,
  // ib, start and entry must be made again. Set by System::Rebuild and the bond calls; cleared by
  // IndexBonds.
  bool stale = true;
  // The intact bonds in the order the pass takes them (q): by the lower storage index of their
  // two spheres, so that it reads the particles nearly in storage order.
  std::vector<int32_t> live;  // index in `bonds` of each intact bond (live)
  // The intact bonds themselves in that order, which the pass steps in place of `bonds` (read at
  // random, their 168 bytes each cost the pass more than all else); copied back by Sync (live).
  std::vector<Bond> hot;
  std::vector<BondConstants> constants;  // (live)
  bool hot_ahead = false;                // `hot` holds newer states than `bonds`
  std::vector<int32_t> ia, ib;           // storage index of its spheres a and b (live)
  // Each particle's bond ends, for the accumulation: particle i owns entries start[i] ..
  // start[i + 1], each 2 q + side (side 0: a, 1: b), in bond order (N + 1; 2 live), so that the
  // sums do not depend on the storage order.
  std::vector<int32_t> start, entry;
  // This step's results of each live bond (BondForces), summed per particle afterwards.
  std::vector<Vec3> force_b;             // force on b [N] (live); a feels its opposite
  std::vector<Vec3> torque_a, torque_b;  // torques about the centres [N m] (live)
  std::vector<uint8_t> event;            // kBroke | kWakeA | kWakeB (live)
  std::vector<int32_t> index_of_id, fill, scratch_a, scratch_b, scratch_pos, scratch_at;  // scratch

  // Brings `bonds` up to date with `hot`: call before anything reads or changes `bonds`.
  void Sync() {
    if (!hot_ahead) return;
    for (size_t q = 0; q < live.size(); ++q) bonds[live[q]] = hot[q];
    hot_ahead = false;
  }
};

// The System's working data (see the top of this file). Array shapes: N particles in storage
// order, num_pairs list pairs, slabs of the neighbour grid.
struct Workspace {
  Stale stale;

  // Contact constants, made once.
  std::vector<PairConstants> pair;  // material pair constants (nm x nm)
  std::vector<PairConstants> wall;  // particle material x plane (nm x num_planes)
  double skin = 0;                  // Verlet-list skin [m] (SystemConfig::skin)

  // The neighbour list and the history of its pairs (Rebuild).
  NeighborList list;
  std::vector<Vec3> shear;        // tangential history of each list pair [m] (num_pairs)
  std::vector<uint8_t> touching;  // the pair touched at the last force evaluation (num_pairs);
                                  // the shear of a pair that did not is stale and reads as zero
  std::vector<Vec3> x_build;      // positions at the last build [m] (N)
  double drift_bound = 0;         // upper bound on any displacement since the last build [m]
  int64_t partial_builds = 0;     // builds of a part of the list (RebuildPart) since the
                                  // System was made or restored (not saved)
  // Whether each particle has been on the active list since the last build (N): only those
  // can have moved, so a sleeper that has not sits exactly at x_build.
  std::vector<uint8_t> moved;
  double asleep_drift = 0;  // largest displacement since the last build of the particles asleep
                            // at the last RefreshActive (they move no more) [m]
  int32_t particle_material = -1;  // the material of every particle, or -1 (Rebuild)
  Alike alike;
  // Whether `alike` still describes the particles: anything that adds or removes one asks for a
  // rebuild, which notes it again.
  bool AlikeNow() const { return alike.all && !stale.rebuild; }

  // The near list: of each visited particle's list pairs, those whose gap (distance - r_i - r_j)
  // was below near_skin when it was made, in list order, packed slot after slot in visiting
  // order (particle i owns slots near_off[i] .. near_off[i] + near_count[i]). No other pair can
  // touch before some particle has moved near_skin / 2, which near_bound (the sum of dt max |v|
  // since it was made) bounds; the force pass scans only these pairs. While the list lives, the
  // slots hold their pairs' history (near_shear, near_touch): the force pass then reads and
  // writes it in one dense stream instead of scattered over the whole list. FlushNear puts it
  // back into shear and touching (Stale::list_history), before anything else reads those or the
  // list changes.
  std::vector<int32_t> near_k;      // list pair index of each slot (num_pairs at most)
  std::vector<int32_t> near_j;      // and its partner
  std::vector<Vec3> near_shear;     // its tangential history [m]
  std::vector<uint8_t> near_touch;  // whether it touched at the last force evaluation
  std::vector<int32_t> near_off;    // first slot of each particle (N)
  std::vector<int32_t> near_count;  // near pairs of each particle (N)
  // Made from near_off and near_count (ListSlotOwners), not saved: the owner of each slot, and
  // each slab's slots slab_slot[s] .. slab_slot[s + 1] (num_slabs + 1), for the force pass's
  // flat walk over the slots. near_owners: they describe the present near list.
  std::vector<int32_t> near_i;
  std::vector<int32_t> slab_slot;
  bool near_owners = false;
  std::vector<int32_t> scratch_near_k;      // BuildNear's first pass (num_pairs)
  double near_skin = 0;                     // [m]
  double near_bound = 0;                    // [m]
  int64_t near_builds = 0, near_pairs = 0;  // near_pairs: the slots in use
  // The force pass's work in each slab (BuildNear): its slots plus its visited particles. Each
  // thread takes one contiguous run of each phase's slabs, split by these weights (ComputeForces).
  std::vector<int64_t> slab_weight;
  SlabRuns slab_runs;

  // Particle-plane contacts near enough to matter (rebuilt with the list), sorted by particle;
  // particle i owns entries wall_start[i] .. wall_start[i + 1].
  std::vector<int32_t> wall_start;     // CSR offsets (N + 1)
  std::vector<int32_t> wall_i;         // particle index
  std::vector<int32_t> wall_k;         // plane index
  std::vector<Vec3> wall_shear;        // tangential history [m]
  std::vector<Vec3> slab_plane_force;  // force on each plane from each slab [N] (slabs x planes)
  // The visited particles with plane candidates, slab by slab (ListWallVisits); the force pass
  // meets the planes through this short list instead of testing every visited particle.
  std::vector<int32_t> wall_visit, slab_wall_visit;

  // Triangle meshes and their contacts (dem/mesh_contact.cpp).
  std::vector<MeshState> meshes;
  int64_t mesh_contacts = 0;
  double mesh_worst = 0;       // deepest particle-mesh overlap / diameter at the last step
  int64_t mesh_worst_id = -1;  // its particle
  int mesh_worst_mesh = -1;    // and mesh

  // Sleeping (dem/sleep.cpp).
  int64_t awake = 0;
  int64_t sleep_counter = 0;    // steps since the last sleep check
  std::vector<int32_t> active;  // storage indices of the awake particles (sleep enabled)
  // With sleeping: the particles that own a list pair with an awake end, or are awake and own
  // wall candidates (the force pass skips the rest), in storage order, and where each slab's run
  // of them starts (slabs + 1). Refreshed when a particle wakes or falls asleep.
  std::vector<int32_t> busy, slab_busy;
  std::vector<uint8_t> scratch_busy;        // RefreshBusy's marks (N)
  std::vector<uint8_t> scratch_slab_awake;  // and whether each slab holds an awake particle

  std::vector<ContactBatch> batches;  // one per thread
  // Each particle's 1/|w| (0 when w = 0) when some pair rolls by the edem model [s/rad] (N): made
  // for the moving particles by KickDrift (or by the force pass, UpdateInvSpins, when that could
  // not), zeroed when a particle falls asleep (its spin with it), so that the pair kernel takes
  // no square root for it.
  std::vector<double> inv_spin;
  // KickDrift makes inv_spin for the particles it moves (want_inv_spin: some pair rolls by
  // edem), so that the force pass need not walk them again; inv_spin_kicked says it did this
  // step and no one moved a spin since (clumps place their spheres after it: System::Step clears
  // it then). Read and cleared by the force pass.
  bool want_inv_spin = false;
  bool inv_spin_kicked = false;

  // Contact history to apply at the next build (a restored state, removed particles).
  std::vector<ContactRecord> pending;
  // The previous build's list and history, kept during a rebuild to carry the history over
  // through the storage permutation.
  std::vector<int32_t> old_start, old_partner, old_wall_start, old_wall_k;
  std::vector<Vec3> old_shear, old_wall_shear;
  std::vector<uint8_t> old_touching;
  std::vector<int32_t> perm, visit, index_of_id;
  std::vector<int32_t> new_of_old;  // inverse of perm (Rebuild)
  // RebuildPart's scratch: the slabs' storage starts at the last build, and on another grid
  // each particle's sort key on it (NeighborList::Regrid).
  std::vector<int32_t> build_slab_start;
  std::vector<int64_t> regrid_key;
  std::vector<double> scratch_d;
  std::vector<int64_t> scratch_i64;
  std::vector<int32_t> scratch_i32;
  std::vector<Vec3> scratch_v;
  std::vector<uint8_t> scratch_u8, scratch_wake, scratch_zone;

  BondWork bond;

  // Per-slab reductions of the force pass (fixed slots, so results do not depend on threads),
  // and their totals.
  std::vector<double> slab_overlap;  // largest overlap / smaller diameter
  std::vector<int64_t> slab_contacts;
  std::vector<int64_t> slab_wall_contacts;
  int64_t contacts = 0, wall_contacts = 0;
  double max_overlap = 0;
};

}  // namespace dem::internal

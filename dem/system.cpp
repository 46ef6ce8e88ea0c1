#include "dem/system.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

#include "dem/contact.h"
#include "dem/grow.h"
#include "dem/neighbor.h"
#include "dem/triangle.h"

namespace dem {

namespace {
// Wall-clock seconds, for PhaseTimes.
double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

// Contacts gathered before one vectorised force evaluation (a block of particles' worth; a
// particle with more near pairs than that comes in pieces).
constexpr int kBatchContacts = 64;  // 40 arrays x 64 x 8 B = 20 KB: stays in L1

// Per-thread scratch of the force pass: the particle-pair contacts of a block of particles,
// gathered so their forces can be computed in one vectorised loop (structure of arrays). Fixed
// arrays in one block: every column sits at a constant offset from one base register.
struct alignas(64) System::ContactBatch {
  static constexpr int K = kBatchContacts;
  // Inputs, gathered by the scalar pass (structure of arrays, one entry per touching pair).
  double dx[K], dy[K], dz[K];     // x_j - x_i [m]
  double dvx[K], dvy[K], dvz[K];  // v_j - v_i [m/s]
  double ax[K], ay[K], az[K];     // r_i w_i + r_j w_j [m/s]
  double wx[K], wy[K], wz[K];     // w_i - w_j [rad/s]
  double ri[K], rj[K];            // radii [m]
  double inv_m_star[K];           // 1/m_i + 1/m_j [1/kg]
  double inv_inertia[K];          // 1/I_i + 1/I_j [1/(kg m^2)]
  double e_star[K], g_star[K], damp[K], tangential_ratio[K], friction[K], rolling[K];
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

// Stores a vector into three structure-of-arrays columns at entry b.
inline void Put(double* cx, double* cy, double* cz, size_t b, const Vec3& a) {
  cx[b] = a.x;
  cy[b] = a.y;
  cz[b] = a.z;
}

// Private state of the System: contact constants, neighbour list, contact history.
struct System::Impl {
  std::vector<PairConstants> pair;  // material pair constants (nm x nm)
  std::vector<PairConstants> wall;  // particle material x plane (nm x num_planes)
  NeighborList list;
  bool list_valid = false;  // list indices refer to the current storage
  bool needs_rebuild = true;
  std::vector<Vec3> shear;        // tangential history of each list pair [m] (num_pairs)
  std::vector<uint8_t> touching;  // the pair touched at the last force evaluation (num_pairs);
                                  // the shear of a pair that did not is stale and reads as zero
  std::vector<Vec3> x_build;      // positions at the last build [m] (N)
  double drift_bound = 0;         // upper bound on any displacement since the last build [m]
  // Whether each particle has been on the active list since the last build (N): only those
  // can have moved, so a sleeper that has not sits exactly at x_build.
  std::vector<uint8_t> moved;
  double asleep_drift = 0;  // largest displacement since the last build of the particles asleep
                            // at the last RefreshActive (they move no more) [m]
  double skin = 0;
  // The near list: of each visited particle's list pairs, those whose gap (distance - r_i - r_j)
  // was below near_skin when it was made, in list order, packed slot after slot in visiting
  // order (particle i owns slots near_off[i] .. near_off[i] + near_count[i]). No other pair can
  // touch before some particle has moved near_skin / 2, which near_bound (the sum of dt max |v|
  // since it was made) bounds; the force pass scans only these pairs. While the list lives, the
  // slots hold their pairs' history (near_shear, near_touch): the force pass then reads and
  // writes it in one dense stream instead of scattered over the whole list. FlushNear puts it
  // back into shear and touching, before anything else reads those or the list changes.
  std::vector<int32_t> near_k;      // list pair index of each slot (num_pairs at most)
  std::vector<int32_t> near_j;      // and its partner
  std::vector<Vec3> near_shear;     // its tangential history [m]
  std::vector<uint8_t> near_touch;  // whether it touched at the last force evaluation
  std::vector<int32_t> near_off;    // first slot of each particle (N)
  std::vector<int32_t> near_count;  // near pairs of each particle (N)
  std::vector<int32_t> scratch_near_k;  // BuildNear's first pass (num_pairs)
  bool near_loaded = false;         // the slots hold the history of their pairs (until Rebuild)
  double near_skin = 0;             // [m]
  double near_bound = 0;            // [m]
  bool near_valid = false;
  int64_t near_builds = 0, near_pairs = 0;  // near_pairs: the slots in use
  double cutoff_radius = 0;  // largest radius the grid was set up for [m]
  size_t grid_capacity = 0;  // particle count the grid was sized for

  // Particle-plane contacts near enough to matter (rebuilt with the list), sorted by particle;
  // particle i owns entries wall_start[i] .. wall_start[i + 1].
  std::vector<int32_t> wall_start;     // CSR offsets (N + 1)
  std::vector<int32_t> wall_i;         // particle index
  std::vector<int32_t> wall_k;         // plane index
  std::vector<Vec3> wall_shear;        // tangential history [m]
  std::vector<Vec3> slab_plane_force;  // force on each plane from each slab [N] (slabs x planes)

  // Triangle meshes and their contacts (see MeshForces).
  struct MeshHistory {
    int32_t index;  // particle storage index
    int64_t id;     // particle persistent id
    Vec3 normal;    // contact normal (particle -> mesh) when the history was stored
    Vec3 shear;     // tangential history [m]
  };
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
    Pose pose_build;            // mesh pose at the candidate build
    double particle_drift = 0;  // bound on particle displacement since the candidate build [m]
    std::vector<MeshHistory> history;  // sorted by particle storage index
    // Per-group results of the parallel pass, summed serially in group order.
    std::vector<Vec3> group_force, group_torque, group_mesh_torque;
    std::vector<double> group_overlap;              // deepest overlap / diameter of each group
    std::vector<int32_t> group_history, group_new;  // history range start; new contacts count
    std::vector<MeshHistory> fresh;                 // new history, up to 4 slots per group
    MeshWrench wrench;
  };
  std::vector<MeshState> meshes;
  int64_t mesh_contacts = 0;
  double mesh_worst = 0;       // deepest particle-mesh overlap / diameter at the last step
  int64_t mesh_worst_id = -1;  // its particle
  int mesh_worst_mesh = -1;    // and mesh
  int64_t awake = 0;
  int64_t sleep_counter = 0;    // steps since the last sleep check
  std::vector<int32_t> active;  // storage indices of the awake particles (sleep enabled)
  // With sleeping: the particles that own a list pair with an awake end, or are awake and own
  // wall candidates (the force pass skips the rest), in storage order, and where each slab's run
  // of them starts (slabs + 1). Refreshed when a particle wakes or falls asleep.
  std::vector<int32_t> busy, slab_busy;
  // The visited particles with plane candidates, slab by slab (ListWallVisits); the force pass
  // meets the planes through this short list instead of testing every visited particle.
  std::vector<int32_t> wall_visit, slab_wall_visit;
  // The force pass's slab order: the even slabs, then (from odd_from) the odd ones, each phase
  // heaviest first (BuildNear).
  std::vector<int32_t> slab_order;
  int odd_from = 0;
  bool walls_valid = false;
  std::vector<uint8_t> scratch_busy;        // RefreshBusy's marks (N)
  std::vector<uint8_t> scratch_slab_awake;  // and whether each slab holds an awake particle
  bool busy_valid = false;
  bool active_valid = false;

  std::vector<ContactBatch> batches;  // one per thread
  int32_t particle_material = -1;     // the material of every particle, or -1 (Rebuild)
  // Every particle alike: one radius, mass and moment of inertia (the common, monodisperse bed;
  // noted at Rebuild). The force pass then reads none of them per partner: a scattered load
  // less per near pair and three per contact, on a bed whose arrays do not fit in the cache.
  bool alike = false;
  double alike_radius = 0, alike_mass = 0, alike_inv_mass = 0, alike_inv_inertia = 0;
  // Whether `alike` still describes the particles: anything that adds or removes one asks for a
  // rebuild, which notes it again.
  bool AlikeNow() const { return alike && !needs_rebuild; }

  std::vector<ContactRecord> pending;  // history to apply at the next build
  // The previous build's list and history, kept during a rebuild to carry the history over
  // through the storage permutation.
  std::vector<int32_t> old_start, old_partner, old_wall_start, old_wall_k;
  std::vector<Vec3> old_shear, old_wall_shear;
  std::vector<uint8_t> old_touching;
  std::vector<int32_t> perm, visit, index_of_id;
  std::vector<int32_t> new_of_old;  // inverse of perm (Rebuild)
  std::vector<double> scratch_d;
  std::vector<int64_t> scratch_i64;
  std::vector<int32_t> scratch_i32;
  std::vector<Vec3> scratch_v;
  std::vector<uint8_t> scratch_u8, scratch_wake, scratch_zone;

  // Per-slab reductions of the force pass (fixed slots, so results do not depend on threads).
  std::vector<double> slab_overlap;  // largest overlap / smaller diameter
  std::vector<int64_t> slab_contacts;
  std::vector<int64_t> slab_wall_contacts;
  int64_t contacts = 0, wall_contacts = 0;
  double max_overlap = 0;
};

System::System(MaterialTable materials, SystemConfig config)
    : materials_(std::move(materials)), config_(std::move(config)), impl_(new Impl) {
  const int nm = materials_.size();
  impl_->pair.resize(nm * nm);
  for (int a = 0; a < nm; ++a)
    for (int b = 0; b < nm; ++b)
      impl_->pair[a * nm + b] =
          MakePairConstants(materials_[a], materials_[b], materials_.interaction(a, b));
  const int np = static_cast<int>(config_.planes.size());
  impl_->wall.resize(nm * np);
  for (int a = 0; a < nm; ++a)
    for (int k = 0; k < np; ++k) {
      const int wm = config_.planes[k].material;
      impl_->wall[a * np + k] =
          MakePairConstants(materials_[a], materials_[wm], materials_.interaction(a, wm));
    }
  plane_force_.assign(np, Vec3{});
  impl_->skin = config_.skin;
  impl_->near_skin = std::max(0.0, config_.near_fraction * config_.skin);  // never below contact
  num_threads_ = omp_get_max_threads();
}

System::~System() { delete impl_; }

void System::Reserve(size_t n) {
  p_.id.reserve(n);
  p_.x.reserve(n);
  p_.v.reserve(n);
  p_.w.reserve(n);
  p_.f.reserve(n);
  p_.t.reserve(n);
  p_.radius.reserve(n);
  p_.mass.reserve(n);
  p_.inv_mass.reserve(n);
  p_.inv_inertia.reserve(n);
  p_.material.reserve(n);
  p_.awake.reserve(n);
}

int64_t System::AddParticle(const Vec3& x, const Vec3& v, const Vec3& w, double radius,
                            int material) {
  const double mass = materials_[material].density * 4.0 / 3.0 * M_PI * radius * radius * radius;
  const int64_t id = next_id_++;
  p_.id.push_back(id);
  p_.x.push_back(x);
  p_.v.push_back(v);
  p_.w.push_back(w);
  p_.f.push_back(mass * config_.gravity);  // force before the first step: gravity alone
  p_.t.push_back(Vec3{});
  p_.radius.push_back(radius);
  p_.mass.push_back(mass);
  p_.inv_mass.push_back(1.0 / mass);
  p_.inv_inertia.push_back(1.0 / (0.4 * mass * radius * radius));
  p_.material.push_back(material);
  p_.awake.push_back(1);
  impl_->needs_rebuild = true;
  impl_->active_valid = false;  // existing list indices stay valid: new particles come last
  return id;
}

void System::RemoveParticles(const std::vector<int64_t>& requested) {
  const std::vector<int64_t> ids = clumps_.RemoveClumpsOf(requested);  // whole clumps
  if (ids.empty()) return;
  std::vector<char> gone(next_id_, 0);
  for (int64_t id : ids)
    if (id >= 0 && id < next_id_) gone[id] = 1;
  std::vector<ContactRecord> keep;
  for (const ContactRecord& c : Contacts())
    if (!gone[c.a] && (c.b < 0 || !gone[c.b])) keep.push_back(c);
  size_t out = 0;
  for (size_t i = 0; i < p_.size(); ++i) {
    if (gone[p_.id[i]]) continue;
    p_.id[out] = p_.id[i];
    p_.x[out] = p_.x[i];
    p_.v[out] = p_.v[i];
    p_.w[out] = p_.w[i];
    p_.f[out] = p_.f[i];
    p_.t[out] = p_.t[i];
    p_.radius[out] = p_.radius[i];
    p_.mass[out] = p_.mass[i];
    p_.inv_mass[out] = p_.inv_mass[i];
    p_.inv_inertia[out] = p_.inv_inertia[i];
    p_.material[out] = p_.material[i];
    p_.awake[out] = p_.awake[i];
    ++out;
  }
  p_.id.resize(out);
  p_.x.resize(out);
  p_.v.resize(out);
  p_.w.resize(out);
  p_.f.resize(out);
  p_.t.resize(out);
  p_.radius.resize(out);
  p_.mass.resize(out);
  p_.inv_mass.resize(out);
  p_.inv_inertia.resize(out);
  p_.material.resize(out);
  p_.awake.resize(out);
  impl_->active_valid = false;
  for (Impl::MeshState& ms : impl_->meshes) {
    size_t kept = 0;
    for (const Impl::MeshHistory& h : ms.history)
      if (!gone[h.id]) ms.history[kept++] = h;
    ms.history.resize(kept);
  }
  impl_->pending = std::move(keep);
  impl_->list_valid = false;
  impl_->needs_rebuild = true;
  clumps_.Reindex(p_, next_id_);
}

void System::Touch() { impl_->needs_rebuild = true; }

NeighborStats System::neighbor_stats() const {
  NeighborStats s;
  s.builds = builds_;
  s.near_builds = impl_->near_builds;
  s.near_pairs = impl_->near_pairs;
  s.pairs = static_cast<int64_t>(impl_->list.num_pairs());
  s.contacts = impl_->contacts;
  s.wall_contacts = impl_->wall_contacts;
  s.mesh_contacts = impl_->mesh_contacts;
  s.awake = config_.sleep.enabled ? impl_->awake : static_cast<int64_t>(p_.size());
  s.max_overlap = impl_->max_overlap;
  return s;
}

namespace {

template <typename T>
void Permute(std::vector<T>& a, const std::vector<int32_t>& perm, std::vector<T>& scratch,
             int num_threads) {
  scratch.resize(a.size());
  const int64_t n = static_cast<int64_t>(perm.size());
  const int32_t* pm = perm.data();
  const T* from = a.data();
  T* to = scratch.data();
#pragma omp parallel for schedule(static) num_threads(num_threads)
  for (int64_t i = 0; i < n; ++i) to[i] = from[pm[i]];
  a.swap(scratch);
}

}  // namespace

// Puts the near slots' history back into the list's arrays (see Impl::near_k).
void System::FlushNear() const {
  Impl& m = *impl_;
  const int num_threads = num_threads_;
  if (!m.near_loaded) return;
  const int32_t* near_k = m.near_k.data();
  const Vec3* near_shear = m.near_shear.data();
  const uint8_t* near_touch = m.near_touch.data();
  Vec3* shear = m.shear.data();
  uint8_t* touching = m.touching.data();
#pragma omp parallel for schedule(static) num_threads(num_threads)
  for (int64_t q = 0; q < m.near_pairs; ++q) {
    shear[near_k[q]] = near_shear[q];
    touching[near_k[q]] = near_touch[q];
  }
}

// The contact history (list pairs, walls, then pending records), sorted by (a, b).
std::vector<ContactRecord> System::Contacts() const {
  std::vector<ContactRecord> out;
  FlushNear();  // moves history only: the state is unchanged
  const Impl& m = *impl_;
  out.reserve(static_cast<size_t>(m.contacts + m.wall_contacts) + m.pending.size());
  if (m.list_valid) {
    const size_t n_listed = m.list.start.empty() ? 0 : m.list.start.size() - 1;
    for (size_t i = 0; i < n_listed; ++i)
      for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k)
        if (m.touching[k] && Norm2(m.shear[k]) > 0.0)
          out.push_back({p_.id[i], p_.id[m.list.partner[k]], m.shear[k]});
    for (size_t e = 0; e < m.wall_i.size(); ++e)
      if (Norm2(m.wall_shear[e]) > 0.0)
        out.push_back(
            {p_.id[m.wall_i[e]], -1 - static_cast<int64_t>(m.wall_k[e]), m.wall_shear[e]});
  }
  out.insert(out.end(), m.pending.begin(), m.pending.end());
  std::sort(out.begin(), out.end(), [](const ContactRecord& l, const ContactRecord& r) {
    return l.a != r.a ? l.a < r.a : l.b < r.b;
  });
  return out;
}

void System::SetContacts(const std::vector<ContactRecord>& contacts) {
  // Replaces all history: the next build takes it from these records only.
  impl_->pending = contacts;
  impl_->list_valid = false;
  impl_->needs_rebuild = true;
}

void System::Rebuild() {
  Impl& m = *impl_;
  const size_t n = p_.size();
  const int nt = num_threads_;
  // 1. Keep the present list and history: they are carried over to the new list through the
  // storage permutation (list indices < n_old have a list; particles added since have none).
  const bool carry = m.list_valid;
  if (carry) FlushNear();
  m.near_loaded = false;
  const int64_t n_old =
      carry && !m.list.start.empty() ? static_cast<int64_t>(m.list.start.size()) - 1 : 0;
  if (carry) {
    m.old_start.swap(m.list.start);
    m.old_partner.swap(m.list.partner);
    m.old_shear.swap(m.shear);
    m.old_touching.swap(m.touching);
    m.old_wall_start.swap(m.wall_start);
    m.old_wall_k.swap(m.wall_k);
    m.old_wall_shear.swap(m.wall_shear);
  }
  // 2. Grid sized for the present particles; reorder storage by cell, ties by persistent id.
  // The grid spans the particles' bounding box (within the domain), so that every slab holds
  // particles and the slabs share the work evenly.
  double r_max = 0;
  double lox = config_.domain_max.x, loy = config_.domain_max.y, loz = config_.domain_max.z;
  double hix = config_.domain_min.x, hiy = config_.domain_min.y, hiz = config_.domain_min.z;
  {
    const Vec3* xs = p_.x.data();
    const double* rs = p_.radius.data();
    const int64_t nn = static_cast<int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(nt) \
    reduction(max : r_max, hix, hiy, hiz) reduction(min : lox, loy, loz)
    for (int64_t i = 0; i < nn; ++i) {
      r_max = std::max(r_max, rs[i]);
      lox = std::min(lox, xs[i].x);
      loy = std::min(loy, xs[i].y);
      loz = std::min(loz, xs[i].z);
      hix = std::max(hix, xs[i].x);
      hiy = std::max(hiy, xs[i].y);
      hiz = std::max(hiz, xs[i].z);
    }
  }
  Vec3 lo{std::max(lox, config_.domain_min.x), std::max(loy, config_.domain_min.y),
          std::max(loz, config_.domain_min.z)};
  Vec3 hi{std::min(hix, config_.domain_max.x), std::min(hiy, config_.domain_max.y),
          std::min(hiz, config_.domain_max.z)};
  if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z)) {
    lo = config_.domain_min;
    hi = config_.domain_max;
  }
  m.list.SetupGrid(lo, hi, 2 * r_max + m.skin, n);
  m.index_of_id.assign(next_id_, -1);
  for (size_t i = 0; i < n; ++i) m.index_of_id[p_.id[i]] = static_cast<int32_t>(i);
  m.visit.clear();
  for (int64_t id = 0; id < next_id_; ++id)
    if (m.index_of_id[id] >= 0) m.visit.push_back(m.index_of_id[id]);
  m.list.ComputeOrder(p_.x.data(), m.visit, &m.perm, nt,
                      config_.sleep.enabled ? p_.awake.data() : nullptr);
  Permute(p_.id, m.perm, m.scratch_i64, nt);
  Permute(p_.x, m.perm, m.scratch_v, nt);
  Permute(p_.v, m.perm, m.scratch_v, nt);
  Permute(p_.w, m.perm, m.scratch_v, nt);
  Permute(p_.f, m.perm, m.scratch_v, nt);
  Permute(p_.t, m.perm, m.scratch_v, nt);
  Permute(p_.radius, m.perm, m.scratch_d, nt);
  Permute(p_.mass, m.perm, m.scratch_d, nt);
  Permute(p_.inv_mass, m.perm, m.scratch_d, nt);
  Permute(p_.inv_inertia, m.perm, m.scratch_d, nt);
  Permute(p_.material, m.perm, m.scratch_i32, nt);
  m.particle_material = n > 0 ? p_.material[0] : -1;
  for (size_t i = 1; i < n && m.particle_material >= 0; ++i)
    if (p_.material[i] != m.particle_material) m.particle_material = -1;
  m.alike = n > 0;
  if (m.alike) {
    m.alike_radius = p_.radius[0];
    m.alike_mass = p_.mass[0];
    m.alike_inv_mass = p_.inv_mass[0];
    m.alike_inv_inertia = p_.inv_inertia[0];
  }
  for (size_t i = 1; i < n && m.alike; ++i)
    m.alike = p_.radius[i] == m.alike_radius && p_.mass[i] == m.alike_mass &&
              p_.inv_mass[i] == m.alike_inv_mass && p_.inv_inertia[i] == m.alike_inv_inertia;
  Permute(p_.awake, m.perm, m.scratch_u8, nt);
  for (size_t i = 0; i < n; ++i) m.index_of_id[p_.id[i]] = static_cast<int32_t>(i);
  // Mesh contact history follows its particles; candidates are found again at the next step.
  for (Impl::MeshState& ms : m.meshes) {
    size_t kept = 0;
    for (Impl::MeshHistory& h : ms.history) {
      if (h.id >= next_id_ || m.index_of_id[h.id] < 0) continue;
      h.index = m.index_of_id[h.id];
      ms.history[kept++] = h;
    }
    ms.history.resize(kept);
    std::stable_sort(
        ms.history.begin(), ms.history.end(),
        [](const Impl::MeshHistory& l, const Impl::MeshHistory& r) { return l.index < r.index; });
    ms.candidates_valid = false;
  }

  // 3. Particle pairs and particle-plane candidates within reach (+ skin).
  // With sleeping, the pairs of two sleepers stay listed (the force pass skips them and keeps
  // their history), so that a particle that wakes needs no rebuild: its pairs are already there.
  const int32_t* clump_of = clumps_.Reindex(p_, next_id_);  // no pairs within a clump
  m.list.Build(p_.x.data(), p_.radius.data(), n, m.skin, nt, clump_of);
  const int64_t num_pairs = static_cast<int64_t>(m.list.num_pairs());
  ResizeWithRoom(m.shear, num_pairs);
  ResizeWithRoom(m.touching, num_pairs);
  const int np = static_cast<int>(config_.planes.size());
  const Plane* planes = config_.planes.data();
  const Vec3* x = p_.x.data();
  const double* radius = p_.radius.data();
  const double skin = m.skin;
  // Particle i is a candidate of plane k (counted here, listed with its history below).
  const auto near_plane = [&](int64_t i, int k) {
    return Dot(x[i] - planes[k].point, planes[k].normal) < radius[i] + skin;
  };
  m.wall_start.resize(n + 1);
  int32_t* wall_start = m.wall_start.data();
  const int64_t nn = static_cast<int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t i = 0; i < nn; ++i) {
    int32_t count = 0;
    for (int k = 0; k < np; ++k) count += near_plane(i, k);
    wall_start[i + 1] = count;
  }
  wall_start[0] = 0;
  for (int64_t i = 0; i < nn; ++i) wall_start[i + 1] += wall_start[i];
  ResizeWithRoom(m.wall_i, wall_start[n]);
  ResizeWithRoom(m.wall_k, wall_start[n]);
  ResizeWithRoom(m.wall_shear, wall_start[n]);

  // 4. Carry the history over: a new pair (i, j) was the old pair of perm[i] and perm[j], owned
  // by the smaller of the two (its shear flips sign if the owner changed). Only pairs that
  // touched with a nonzero spring carry anything; every other pair starts afresh. So the old
  // list is walked (in storage order) and each such pair is looked up in the new one: one new
  // pair per old pair, so the writes never meet.
  {
    const int32_t* start = m.list.start.data();
    const int32_t* partner = m.list.partner.data();
    const int32_t* perm = m.perm.data();
    const int32_t* o_start = m.old_start.data();
    const int32_t* o_partner = m.old_partner.data();
    const Vec3* o_shear = m.old_shear.data();
    const uint8_t* o_touching = m.old_touching.data();
    const int32_t* o_wall_start = m.old_wall_start.data();
    const int32_t* o_wall_k = m.old_wall_k.data();
    const Vec3* o_wall_shear = m.old_wall_shear.data();
    Vec3* shear = m.shear.data();
    uint8_t* touching = m.touching.data();
    int32_t* wall_i = m.wall_i.data();
    int32_t* wall_k = m.wall_k.data();
    Vec3* wall_shear = m.wall_shear.data();
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t k = 0; k < num_pairs; ++k) {
      shear[k] = Vec3{};
      touching[k] = 0;
    }
    if (carry) {
      m.new_of_old.resize(n);
      int32_t* new_of_old = m.new_of_old.data();
#pragma omp parallel for schedule(static) num_threads(nt)
      for (int64_t i = 0; i < nn; ++i) new_of_old[perm[i]] = static_cast<int32_t>(i);
#pragma omp parallel for schedule(static) num_threads(nt)
      for (int64_t oi = 0; oi < n_old; ++oi) {
        for (int32_t q = o_start[oi]; q < o_start[oi + 1]; ++q) {
          if (!(o_touching[q] && Norm2(o_shear[q]) > 0.0)) continue;
          const int32_t a = new_of_old[oi], b = new_of_old[o_partner[q]];
          const int32_t owner = std::min(a, b), other = std::max(a, b);
          for (int32_t k = start[owner]; k < start[owner + 1]; ++k)
            if (partner[k] == other) {
              shear[k] = owner == a ? o_shear[q] : -o_shear[q];
              touching[k] = 1;
              break;
            }
        }
      }
    }
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = 0; i < nn; ++i) {
      const int32_t oi = perm[i];
      int32_t e = wall_start[i];
      for (int k = 0; k < np; ++k) {
        if (!near_plane(i, k)) continue;
        wall_i[e] = static_cast<int32_t>(i);
        wall_k[e] = k;
        wall_shear[e] = Vec3{};
        if (carry && oi < n_old)
          for (int32_t q = o_wall_start[oi]; q < o_wall_start[oi + 1]; ++q)
            if (o_wall_k[q] == k && Norm2(o_wall_shear[q]) > 0.0) wall_shear[e] = o_wall_shear[q];
        ++e;
      }
    }
  }

  // 5. Put the pending history (a restored state, removed particles) on the new entries.
  for (const ContactRecord& c : m.pending) {
    if (c.a < 0 || c.a >= next_id_) continue;
    const int32_t ia = m.index_of_id[c.a];
    if (ia < 0) continue;
    if (c.b >= 0) {
      if (c.b >= next_id_ || m.index_of_id[c.b] < 0) continue;
      const int32_t ib = m.index_of_id[c.b];
      const int32_t owner = std::min(ia, ib), other = std::max(ia, ib);
      for (int32_t k = m.list.start[owner]; k < m.list.start[owner + 1]; ++k)
        if (m.list.partner[k] == other) {
          m.shear[k] = owner == ia ? c.shear : -c.shear;
          m.touching[k] = 1;
          break;
        }
    } else {
      const int32_t plane = static_cast<int32_t>(-1 - c.b);
      for (int32_t e = m.wall_start[ia]; e < m.wall_start[ia + 1]; ++e)
        if (m.wall_k[e] == plane) m.wall_shear[e] = c.shear;
    }
  }
  m.pending.clear();
  m.x_build.resize(n);
  {
    Vec3* xb = m.x_build.data();
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = 0; i < nn; ++i) xb[i] = x[i];
  }
  m.drift_bound = 0;
  m.asleep_drift = 0;
  m.moved.assign(n, 0);  // RefreshActive marks the particles it lets move
  m.list_valid = true;
  m.needs_rebuild = false;
  m.active_valid = false;
  m.busy_valid = false;
  m.near_valid = false;
  m.walls_valid = false;
  ++builds_;
  // The arrays the force pass reads at random, on 2 MB pages where the system allows it.
  for (const auto* a : {&p_.x, &p_.v, &p_.w, &p_.f, &p_.t, &m.shear, &m.x_build})
    AdviseHugePages(*a);
  for (const auto* a : {&p_.radius, &p_.mass, &p_.inv_mass, &p_.inv_inertia}) AdviseHugePages(*a);
  for (const auto* a : {&m.list.start, &m.list.partner, &p_.material}) AdviseHugePages(*a);
}

void System::RefreshBusy() {
  Impl& m = *impl_;
  const uint8_t* awake = p_.awake.data();
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  const int32_t* wall_start = m.wall_start.data();
  const int ns = m.list.num_slabs();
  const int64_t n = static_cast<int64_t>(p_.size());
  // Mark, count per slab, then list in storage order (each step in parallel; the result depends
  // on the data only).
  std::vector<uint8_t>& flag = m.scratch_busy;
  flag.resize(n);
  // A pair's partner lies in its owner's slab or the next, so a slab is busy-free when neither
  // it nor the next holds an awake particle: its lists need not be read (most slabs of a
  // sleeping bed).
  std::vector<uint8_t>& slab_awake = m.scratch_slab_awake;
  slab_awake.assign(ns + 1, 0);
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl)
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i)
      if (awake[i]) {
        slab_awake[sl] = 1;
        break;
      }
#pragma omp parallel for schedule(dynamic, 4) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl) {
    const int32_t lo = m.list.slab_start[sl], hi = m.list.slab_start[sl + 1];
    if (!slab_awake[sl] && !slab_awake[sl + 1]) {
      std::fill(flag.begin() + lo, flag.begin() + hi, uint8_t{0});
      continue;
    }
    for (int32_t i = lo; i < hi; ++i) {
      bool busy = awake[i] && wall_start[i + 1] > wall_start[i];
      for (int32_t k = start[i]; k < start[i + 1] && !busy; ++k)
        busy = awake[i] || awake[partner[k]];
      flag[i] = busy;
    }
  }
  m.slab_busy.assign(ns + 1, 0);
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl) {
    int32_t count = 0;
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i) count += flag[i];
    m.slab_busy[sl + 1] = count;
  }
  for (int sl = 0; sl < ns; ++sl) m.slab_busy[sl + 1] += m.slab_busy[sl];
  ResizeWithRoom(m.busy, m.slab_busy[ns]);
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl) {
    int32_t at = m.slab_busy[sl];
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i)
      if (flag[i]) m.busy[at++] = i;
  }
  m.busy_valid = true;
  m.near_valid = false;   // the near list covers the busy particles only
  m.walls_valid = false;  // and so does the wall list
}

void System::ListWallVisits() {
  Impl& m = *impl_;
  const bool compact = config_.sleep.enabled;
  const int ns = m.list.num_slabs();
  const int32_t* wall_start = m.wall_start.data();
  const int32_t* busy = m.busy.data();
  m.slab_wall_visit.assign(ns + 1, 0);
  // Count per slab, then list in visiting order (each in parallel; the result depends on the
  // data only).
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl) {
    const int32_t lo = compact ? m.slab_busy[sl] : m.list.slab_start[sl];
    const int32_t hi = compact ? m.slab_busy[sl + 1] : m.list.slab_start[sl + 1];
    int32_t count = 0;
    for (int32_t at = lo; at < hi; ++at) {
      const int32_t i = compact ? busy[at] : at;
      count += wall_start[i + 1] > wall_start[i];
    }
    m.slab_wall_visit[sl + 1] = count;
  }
  for (int sl = 0; sl < ns; ++sl) m.slab_wall_visit[sl + 1] += m.slab_wall_visit[sl];
  ResizeWithRoom(m.wall_visit, m.slab_wall_visit[ns]);
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int sl = 0; sl < ns; ++sl) {
    const int32_t lo = compact ? m.slab_busy[sl] : m.list.slab_start[sl];
    const int32_t hi = compact ? m.slab_busy[sl + 1] : m.list.slab_start[sl + 1];
    int32_t out = m.slab_wall_visit[sl];
    for (int32_t at = lo; at < hi; ++at) {
      const int32_t i = compact ? busy[at] : at;
      if (wall_start[i + 1] > wall_start[i]) m.wall_visit[out++] = i;
    }
  }
  m.walls_valid = true;
}

void System::BuildNear() {
  Impl& m = *impl_;
  FlushNear();  // the old slots' history first: the new slots take it from the list's arrays
  const size_t n = p_.size();
  ResizeWithRoom(m.scratch_near_k, m.list.num_pairs());
  m.near_count.resize(n);
  m.near_off.resize(n);
  const Vec3* x = p_.x.data();
  const double* radius = p_.radius.data();
  const uint8_t* awake = p_.awake.data();
  const bool sleeping = config_.sleep.enabled;
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  int32_t* sparse_k = m.scratch_near_k.data();
  int32_t* near_count = m.near_count.data();
  int32_t* near_off = m.near_off.data();
  uint8_t* touched = m.touching.data();
  const double s = m.near_skin;
  // With sleeping, only the particles the force pass visits (RefreshBusy makes the list again
  // when that set changes).
  const int32_t* busy = m.busy.data();
  const int64_t visits = sleeping ? static_cast<int64_t>(m.busy.size()) : static_cast<int64_t>(n);
  // 1. The near pairs of each particle, at the front of its list range.
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int64_t a = 0; a < visits; ++a) {
    const int64_t i = sleeping ? busy[a] : a;
    const Vec3 xi = x[i];
    const double ri = radius[i];
    const bool awake_i = !sleeping || awake[i];
    int32_t at = start[i];
    for (int32_t k = start[i]; k < start[i + 1]; ++k) {
      const int32_t j = partner[k];
      // Two sleepers do not interact (the force pass would skip their pair and keep its
      // history), so a sleeper lists only its awake partners; a wake refreshes this list.
      if (!awake_i && !awake[j]) continue;
      const double reach = ri + radius[j] + s;
      if (Norm2(x[j] - xi) < reach * reach) {
        sparse_k[at++] = k;
      } else {
        touched[k] = 0;  // as the force pass would mark it: not touching
      }
    }
    near_count[i] = at - start[i];
  }
  // 2. Pack them slot after slot in visiting order, each with its pair's history.
  const int ns = m.list.num_slabs();
  std::vector<int64_t> weight(ns);
  int64_t slots = 0;
  for (int sl = 0; sl < ns; ++sl) {
    const int64_t lo = sleeping ? m.slab_busy[sl] : m.list.slab_start[sl];
    const int64_t hi = sleeping ? m.slab_busy[sl + 1] : m.list.slab_start[sl + 1];
    const int64_t before = slots;
    for (int64_t a = lo; a < hi; ++a) {
      const int64_t i = sleeping ? busy[a] : a;
      near_off[i] = static_cast<int32_t>(slots);
      slots += near_count[i];
    }
    weight[sl] = slots - before + (hi - lo);  // the force pass's work: pairs and particles
  }
  // The force pass hands out each phase's slabs heaviest first, so that the last ones, those
  // that may leave a thread waiting, are light (with sleeping the work sits in a few slabs).
  m.slab_order.resize(ns);
  for (int sl = 0; sl < ns; ++sl) m.slab_order[sl] = sl;
  const auto phase_end = std::stable_partition(m.slab_order.begin(), m.slab_order.end(),
                                               [](int32_t sl) { return sl % 2 == 0; });
  const auto heavier = [&](int32_t a, int32_t b) { return weight[a] > weight[b]; };
  std::stable_sort(m.slab_order.begin(), phase_end, heavier);
  std::stable_sort(phase_end, m.slab_order.end(), heavier);
  m.odd_from = static_cast<int>(phase_end - m.slab_order.begin());
  ResizeWithRoom(m.near_k, slots);
  ResizeWithRoom(m.near_j, slots);
  ResizeWithRoom(m.near_shear, slots);
  ResizeWithRoom(m.near_touch, slots);
  int32_t* near_k = m.near_k.data();
  int32_t* near_j = m.near_j.data();
  Vec3* near_shear = m.near_shear.data();
  uint8_t* near_touch = m.near_touch.data();
  const Vec3* shear = m.shear.data();
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int64_t a = 0; a < visits; ++a) {
    const int64_t i = sleeping ? busy[a] : a;
    for (int32_t c = 0; c < near_count[i]; ++c) {
      const int32_t k = sparse_k[start[i] + c];
      const int32_t q = near_off[i] + c;
      near_k[q] = k;
      near_j[q] = partner[k];
      near_shear[q] = shear[k];
      near_touch[q] = touched[k];
    }
  }
  m.near_loaded = true;
  m.near_bound = 0;
  m.near_valid = true;
  ++m.near_builds;
  m.near_pairs = slots;
}

// Hertz-Mindlin forces of a batch of particle pairs: the same law as EvaluateContact
// (dem/contact.h), written without branches so that the compiler runs one contact per SIMD lane.
template <bool kOnePair>
void System::PairForces(ContactBatch& b, size_t nb, const PairConstants& one) {
  const double dt = config_.time_step;
  ContactBatch& __restrict c = b;
  const int n = static_cast<int>(nb);
  // The pair constants: the one pair's, broadcast, or each contact's own column.
  const auto pick = [](double scalar, const double* column, int e) {
    return kOnePair ? scalar : column[e];
  };
#pragma omp simd
  for (int e = 0; e < n; ++e) {
    const double e_star = pick(one.e_star, c.e_star, e), g_star = pick(one.g_star, c.g_star, e);
    const double damp = pick(one.damp, c.damp, e);
    const double tangential_ratio = pick(one.tangential_ratio, c.tangential_ratio, e);
    const double friction = pick(one.friction, c.friction, e);
    const double rolling = pick(one.rolling_friction, c.rolling, e);
    const double dx = c.dx[e], dy = c.dy[e], dz = c.dz[e];
    const double ri = c.ri[e], rj = c.rj[e];
    const double dist = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double inv_d = 1.0 / dist;
    const double nx = dx * inv_d, ny = dy * inv_d, nz = dz * inv_d;  // from i to j
    const double delta = ri + rj - dist;
    const double r_star = ri * rj / (ri + rj);
    // Contact-point velocity of j relative to i: (v_j - v_i) - (r_i w_i + r_j w_j) x n.
    const double ax = c.ax[e], ay = c.ay[e], az = c.az[e];
    const double vx = c.dvx[e] - (ay * nz - az * ny);
    const double vy = c.dvy[e] - (az * nx - ax * nz);
    const double vz = c.dvz[e] - (ax * ny - ay * nx);
    const double vn = vx * nx + vy * ny + vz * nz;
    const double vtx = vx - vn * nx, vty = vy - vn * ny, vtz = vz - vn * nz;
    // Normal: Hertz spring + damping, no tension.
    const double sq = std::sqrt(r_star * delta);
    const double sn = 2.0 * e_star * sq;
    const double gamma_n = damp * std::sqrt(sn / c.inv_m_star[e]);
    const double fn = std::max(0.0, 2.0 / 3.0 * sn * delta - gamma_n * vn);
    // Tangential history: back into the tangent plane at its old length, plus v_t dt.
    double sx = c.sx[e], sy = c.sy[e], sz = c.sz[e];
    const double xi_n = sx * nx + sy * ny + sz * nz;
    sx -= xi_n * nx;
    sy -= xi_n * ny;
    sz -= xi_n * nz;
    const double new2 = sx * sx + sy * sy + sz * sz;
    const double q = new2 > 0.0 ? xi_n * xi_n / new2 : 0.0;
    const double scale = q < 1e-4 ? 1.0 + q * (0.5 - 0.125 * q) : std::sqrt(1.0 + q);
    sx = sx * scale + dt * vtx;
    sy = sy * scale + dt * vty;
    sz = sz * scale + dt * vtz;
    // Mindlin spring + damping, Coulomb cap (the spring then carries the friction force).
    const double st = 4.0 * g_star / e_star * sn;
    const double gamma_t = tangential_ratio * gamma_n;
    double ftx = st * sx + gamma_t * vtx, fty = st * sy + gamma_t * vty,
           ftz = st * sz + gamma_t * vtz;
    const double ft2 = ftx * ftx + fty * fty + ftz * ftz;
    const double cap = friction * fn;
    const bool slide = ft2 > cap * cap;
    const double ratio = slide ? cap / std::sqrt(ft2) : 1.0;
    ftx *= ratio;
    fty *= ratio;
    ftz *= ratio;
    const double inv_st = 1.0 / st;
    c.sx[e] = slide ? ftx * inv_st : sx;
    c.sy[e] = slide ? fty * inv_st : sy;
    c.sz[e] = slide ? ftz * inv_st : sz;
    // Rolling friction against the relative rotation, limited so it cannot reverse it.
    const double wrx = c.wx[e], wry = c.wy[e], wrz = c.wz[e];
    const double w2 = wrx * wrx + wry * wry + wrz * wrz;
    const double wn = std::sqrt(w2);
    const double mr_mag = std::min(rolling * r_star * fn, wn / (dt * c.inv_inertia[e]));
    const double mr_f = (rolling > 0.0 && w2 > 0.0) ? -mr_mag / wn : 0.0;
    const double mrx = mr_f * wrx, mry = mr_f * wry, mrz = mr_f * wrz;
    // Force on i and the torques on both.
    c.fx[e] = ftx - fn * nx;
    c.fy[e] = fty - fn * ny;
    c.fz[e] = ftz - fn * nz;
    const double cx = ny * ftz - nz * fty, cy = nz * ftx - nx * ftz, cz = nx * fty - ny * ftx;
    c.tix[e] = ri * cx + mrx;
    c.tiy[e] = ri * cy + mry;
    c.tiz[e] = ri * cz + mrz;
    c.tjx[e] = rj * cx - mrx;
    c.tjy[e] = rj * cy - mry;
    c.tjz[e] = rj * cz - mrz;
    c.overlap[e] = delta / (2.0 * std::min(ri, rj));
  }
}

void System::ComputeForces() {
  Impl& m = *impl_;
  const double dt = config_.time_step;
  const int nm = materials_.size();
  const PairConstants* pc = m.pair.data();
  const int nslabs = m.list.num_slabs();
  const int np = static_cast<int>(config_.planes.size());
  m.slab_overlap.assign(nslabs, 0.0);
  m.slab_contacts.assign(nslabs, 0);
  m.slab_wall_contacts.assign(nslabs, 0);
  m.slab_plane_force.assign(static_cast<size_t>(nslabs) * np, Vec3{});

  Vec3* __restrict f = p_.f.data();
  Vec3* __restrict t = p_.t.data();
  const Vec3* x = p_.x.data();
  const Vec3* v = p_.v.data();
  const Vec3* w = p_.w.data();
  const double* radius = p_.radius.data();
  const double* mass = p_.mass.data();
  const double* inv_mass = p_.inv_mass.data();
  const double* inv_inertia = p_.inv_inertia.data();
  const int32_t* mat = p_.material.data();
  const int32_t* wall_start = m.wall_start.data();
  const int32_t* wall_k = m.wall_k.data();
  Vec3* wall_shear = m.wall_shear.data();
  const Plane* planes = config_.planes.data();

  const bool compact = config_.sleep.enabled;
  const bool one_material = m.particle_material >= 0;
  const bool alike = m.alike;  // each sum below is the one the per-particle arrays would give
  const double alike_rsum = m.alike_radius + m.alike_radius;
  const double alike_inv_m_star = m.alike_inv_mass + m.alike_inv_mass;
  const double alike_inv_inertia = m.alike_inv_inertia + m.alike_inv_inertia;
  const double t_near = Now();
  if (compact && !m.busy_valid) RefreshBusy();
  if (!m.near_valid) BuildNear();
  if (!m.walls_valid) ListWallVisits();
  const double t_pairs = Now();
  phase_times_.near += t_pairs - t_near;
  const int32_t* wall_visit = m.wall_visit.data();
  const int32_t* near_j = m.near_j.data();
  const int32_t* near_off = m.near_off.data();
  const int32_t* near_count = m.near_count.data();
  Vec3* shear = m.near_shear.data();       // the near slots hold the history (Impl::near_k)
  uint8_t* touched = m.near_touch.data();
  const int32_t* busy = m.busy.data();
  const uint8_t* awake = p_.awake.data();
  if (m.batches.size() < static_cast<size_t>(num_threads_)) m.batches.resize(num_threads_);

#pragma omp parallel num_threads(num_threads_)
  {
    // Even slabs, then odd slabs (see neighbor.h for why this is race-free and deterministic).
    for (int phase = 0; phase < 2; ++phase) {
      const int first = phase == 0 ? 0 : m.odd_from, last = phase == 0 ? m.odd_from : nslabs;
#pragma omp for schedule(dynamic, 1)
      for (int at_slab = first; at_slab < last; ++at_slab) {
        const int s = m.slab_order[at_slab];  // heaviest first (BuildNear)
        double worst = 0;
        int64_t touching = 0, wall_touching = 0;
        Vec3* plane_force = m.slab_plane_force.data() + static_cast<size_t>(s) * np;
        ContactBatch& batch = m.batches[omp_get_thread_num()];
        // Particles are visited by position in the slab (all of them), or, with sleeping, through
        // the list of busy ones.
        const int32_t slab_end = compact ? m.slab_busy[s + 1] : m.list.slab_start[s + 1];
        int32_t block = compact ? m.slab_busy[s] : m.list.slab_start[s];
        int32_t resume = 0;  // near pairs of the block's first particle already done (pieces)
        while (block < slab_end) {
          // 1. Find the touching pairs of a block of particles without branching on the
          //    outcome (a contact is a coin toss for the branch predictor): write every
          //    candidate at slot nb and advance nb only for a contact. `touching` remembers
          //    which pairs touched at the last step; a pair that comes into contact starts with
          //    no tangential history.
          size_t nb = 0;
          int32_t block_end = block;
          bool piece = false;  // the batch ends inside the near pairs of busy[block_end]
          int32_t q_end = 0;
          for (; block_end < slab_end; ++block_end) {
            const int32_t i = compact ? busy[block_end] : block_end;
            const int32_t q_begin = near_off[i] + (block_end == block ? resume : 0);
            q_end = near_off[i] + near_count[i];
            if (nb + static_cast<size_t>(q_end - q_begin) > ContactBatch::K) {
              if (nb > 0) break;  // the next batch takes it
              q_end = q_begin + ContactBatch::K;
              piece = true;
            }
            const Vec3 xi = x[i];
            const double ri = radius[i];
            // Only the near pairs can touch (see Impl::near_k); none joins two sleepers (the
            // near list is made again whenever a particle wakes or falls asleep).
            for (int32_t q = q_begin; q < q_end; ++q) {
              const int32_t j = near_j[q];
              const double rsum = alike ? alike_rsum : ri + radius[j];
              const bool contact = Norm2(x[j] - xi) < rsum * rsum;
              batch.i[nb] = i;
              batch.j[nb] = j;
              batch.k[nb] = q;
              batch.was[nb] = touched[q];
              touched[q] = contact;
              nb += contact;
            }
            if (piece) break;
          }
          // Gather what the force law needs, one contact at a time (no branches). When all the
          // particles are of one material (the common case), so is every pair.
          bool uniform = true;
          for (size_t b = 0; b < nb; ++b) {
            const int32_t i = batch.i[b], j = batch.j[b], k = batch.k[b];
            if (!one_material) {
              const int32_t pair = mat[i] * nm + mat[j];
              batch.pair[b] = pair;
              uniform = uniform && pair == batch.pair[0];
            }
            const double ri = alike ? m.alike_radius : radius[i];
            const double rj = alike ? m.alike_radius : radius[j];
            Put(batch.dx, batch.dy, batch.dz, b, x[j] - x[i]);
            Put(batch.dvx, batch.dvy, batch.dvz, b, v[j] - v[i]);
            Put(batch.ax, batch.ay, batch.az, b, ri * w[i] + rj * w[j]);
            Put(batch.wx, batch.wy, batch.wz, b, w[i] - w[j]);
            batch.ri[b] = ri;
            batch.rj[b] = rj;
            batch.inv_m_star[b] = alike ? alike_inv_m_star : inv_mass[i] + inv_mass[j];
            batch.inv_inertia[b] = alike ? alike_inv_inertia : inv_inertia[i] + inv_inertia[j];
            Put(batch.sx, batch.sy, batch.sz, b, (batch.was[b] ? 1.0 : 0.0) * shear[k]);
          }
          // 2. Contact forces of the batch, one contact per SIMD lane (EvaluateContact, written
          //    without branches), with one material pair's constants for all (the common case)
          //    or each contact's own.
          if (one_material) {
            PairForces<true>(batch, nb, pc[m.particle_material * nm + m.particle_material]);
          } else if (nb > 0 && uniform) {
            PairForces<true>(batch, nb, pc[batch.pair[0]]);
          } else {
            for (size_t b = 0; b < nb; ++b) {
              const PairConstants& c = pc[batch.pair[b]];
              batch.e_star[b] = c.e_star;
              batch.g_star[b] = c.g_star;
              batch.damp[b] = c.damp;
              batch.tangential_ratio[b] = c.tangential_ratio;
              batch.friction[b] = c.friction;
              batch.rolling[b] = c.rolling_friction;
            }
            PairForces<false>(batch, nb, pc[0]);
          }
          // 3. Accumulate in batch order (fixed by the data: deterministic).
          for (size_t b = 0; b < nb; ++b) {
            const int32_t i = batch.i[b], j = batch.j[b];
            shear[batch.k[b]] = Vec3{batch.sx[b], batch.sy[b], batch.sz[b]};
            const Vec3 fa{batch.fx[b], batch.fy[b], batch.fz[b]};
            f[i] += fa;
            f[j] -= fa;
            t[i] += Vec3{batch.tix[b], batch.tiy[b], batch.tiz[b]};
            t[j] += Vec3{batch.tjx[b], batch.tjy[b], batch.tjz[b]};
            worst = std::max(worst, batch.overlap[b]);
          }
          touching += static_cast<int64_t>(nb);
          if (piece) {  // go on with the same particle
            const int32_t i = compact ? busy[block_end] : block_end;
            resume = q_end - near_off[i];
            block = block_end;
          } else {
            resume = 0;
            block = block_end;
          }
        }
        // 4. The planes, after all the slab's pairs: a later block's pairs never reach back
        //    to an earlier particle (j > i), so each sum adds up in the same order as if the
        //    planes came right after their particle's block.
        for (int32_t a = m.slab_wall_visit[s]; a < m.slab_wall_visit[s + 1]; ++a) {
          const int32_t i = wall_visit[a];
          if (!awake[i]) continue;
          const Vec3 xi = x[i], vi = v[i], wi = w[i];
          const double ri = radius[i], mi = mass[i], inv_ii = inv_inertia[i];
          Vec3 fi, ti;
          // Particle-plane contacts of i (R* = r_i, m* = m_i: the wall is rigid and fixed).
          for (int32_t e = wall_start[i]; e < wall_start[i + 1]; ++e) {
            const Plane& pl = planes[wall_k[e]];
            const double delta = ri - Dot(xi - pl.point, pl.normal);
            if (delta <= 0.0) {
              wall_shear[e] = Vec3{};
              continue;
            }
            const Vec3 nrm = -pl.normal;  // from the particle to the wall
            const Vec3 v_rel = -(vi + ri * Cross(wi, nrm));
            const ContactForce cf = EvaluateContact(m.wall[mat[i] * np + wall_k[e]], nrm, delta,
                                                    ri, mi, v_rel, wi, inv_ii, dt, wall_shear[e]);
            const Vec3 fa = cf.ft - cf.fn * nrm;
            fi += fa;
            ti += ri * Cross(nrm, cf.ft) + cf.mr;
            plane_force[wall_k[e]] -= fa;
            worst = std::max(worst, delta / (2.0 * ri));
            ++wall_touching;
          }
          f[i] += fi;
          t[i] += ti;
        }
        m.slab_overlap[s] = worst;
        m.slab_contacts[s] = touching;
        m.slab_wall_contacts[s] = wall_touching;
      }
    }
  }
  // Reductions over slabs in slab order (independent of the thread count).
  std::fill(plane_force_.begin(), plane_force_.end(), Vec3{});
  m.contacts = m.wall_contacts = 0;
  double worst = 0;
  for (int s = 0; s < nslabs; ++s) {
    for (int k = 0; k < np; ++k)
      plane_force_[k] += m.slab_plane_force[static_cast<size_t>(s) * np + k];
    m.contacts += m.slab_contacts[s];
    m.wall_contacts += m.slab_wall_contacts[s];
    worst = std::max(worst, m.slab_overlap[s]);
  }
  m.max_overlap = worst;
  phase_times_.pairs += Now() - t_pairs;
}

StepStatus System::Step() {
  Impl& m = *impl_;
  const size_t n = p_.size();
  const double dt = config_.time_step;
  const double h = 0.5 * dt;
  Vec3* x = p_.x.data();
  Vec3* v = p_.v.data();
  Vec3* w = p_.w.data();
  Vec3* f = p_.f.data();
  Vec3* t = p_.t.data();
  const double* mass = p_.mass.data();
  const double* inv_mass = p_.inv_mass.data();
  const double* inv_inertia = p_.inv_inertia.data();
  const Vec3 g = config_.gravity;

  // Velocity Verlet (LIGGGHTS fix nve/sphere; Allen & Tildesley eq. 3.19): half kick, drift.
  // With sleeping, only the awake particles (m.active) move; a sleeper's force and torque are
  // not kept up to date (they are zeroed when it wakes: a sleeper is at rest in equilibrium).
  double max_v2 = 0;
  const bool sleeping = config_.sleep.enabled;
  double t_phase = Now();
  auto lap = [&t_phase](double& phase) {  // adds the time since the last lap to `phase`
    const double now = Now();
    phase += now - t_phase;
    t_phase = now;
  };
  if (sleeping && !m.active_valid) RefreshActive();
  lap(phase_times_.sleep);
  const int32_t* active = m.active.data();
  const int64_t n_moving =
      sleeping ? static_cast<int64_t>(m.active.size()) : static_cast<int64_t>(n);
  // Alike particles (Impl::AlikeNow): the same numbers as the per-particle arrays hold, without
  // streaming them.
  bool alike = m.AlikeNow();
  double alike_mass = m.alike_mass, alike_inv_mass = m.alike_inv_mass,
         alike_inv_inertia = m.alike_inv_inertia;
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(max : max_v2)
  for (int64_t a = 0; a < n_moving; ++a) {
    const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
    v[i] += (h * (alike ? alike_inv_mass : inv_mass[i])) * f[i];
    w[i] += (h * (alike ? alike_inv_inertia : inv_inertia[i])) * t[i];
    x[i] += dt * v[i];
    max_v2 = std::max(max_v2, Norm2(v[i]));
    // Start this step's force with gravity (contacts add to it in ComputeForces).
    f[i] = (alike ? alike_mass : mass[i]) * g;
    t[i] = Vec3{};
  }
  if (!clumps_.empty()) {  // rigid clumps (dem/clump.h): move the bodies, place their spheres
    const ClumpSet::BeginReport r = clumps_.BeginStep(p_, dt, num_threads_);
    max_v2 = std::max(max_v2, r.max_member_speed2);
    if (r.woke) {  // their pairs are listed: only the visiting lists change
      m.busy_valid = false;
      m.active_valid = false;
    }
  }
  // Rebuild when some particle has moved more than skin/2 since the last build. The sum of
  // dt * max |v| bounds every displacement (triangle inequality); only when that bound passes
  // skin/2 are the true displacements measured, and the bound restarts from the largest one.
  const double half_skin = 0.5 * m.skin;
  const bool have_build = m.list_valid && m.x_build.size() == n;
  m.drift_bound += dt * std::sqrt(max_v2);
  bool rebuild = m.needs_rebuild || !have_build;
  if (!rebuild && m.drift_bound > half_skin) {
    // With sleeping only the awake particles can have moved on; the sleepers' share is kept in
    // asleep_drift.
    double max_disp2 = m.asleep_drift * m.asleep_drift;
    const Vec3* xb = m.x_build.data();
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(max : max_disp2)
    for (int64_t a = 0; a < n_moving; ++a) {
      const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
      max_disp2 = std::max(max_disp2, Norm2(x[i] - xb[i]));
    }
    m.drift_bound = std::sqrt(max_disp2);
    rebuild = !(m.drift_bound <= half_skin);  // also on NaN
  }
  for (Impl::MeshState& ms : m.meshes) ms.particle_drift += dt * std::sqrt(max_v2);
  m.near_bound += dt * std::sqrt(max_v2);
  if (!(m.near_bound <= 0.5 * m.near_skin)) m.near_valid = false;  // also on NaN
  lap(phase_times_.integrate);
  if (rebuild) {
    Rebuild();
    lap(phase_times_.rebuild);
  }

  ComputeForces();  // adds its own phases (near, pairs)
  t_phase = Now();
  if (!m.meshes.empty()) {
    MeshForces();
    lap(phase_times_.mesh);
  }

  // Second half kick, with health checks.
  v = p_.v.data();
  w = p_.w.data();
  f = p_.f.data();
  t = p_.t.data();
  inv_mass = p_.inv_mass.data();
  inv_inertia = p_.inv_inertia.data();
  if (sleeping && !m.active_valid) RefreshActive();
  active = m.active.data();
  lap(phase_times_.sleep);
  const int64_t n_kicked =
      sleeping ? static_cast<int64_t>(m.active.size()) : static_cast<int64_t>(n);
  max_v2 = 0;
  int bad = 0;
  alike = m.AlikeNow();  // noted again if this step rebuilt
  alike_inv_mass = m.alike_inv_mass;
  alike_inv_inertia = m.alike_inv_inertia;
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(max       \
                                                                              : max_v2) \
    reduction(|                                                                         \
              : bad)
  for (int64_t a = 0; a < n_kicked; ++a) {
    const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
    v[i] += (h * (alike ? alike_inv_mass : inv_mass[i])) * f[i];
    w[i] += (h * (alike ? alike_inv_inertia : inv_inertia[i])) * t[i];
    const double v2 = Norm2(v[i]);
    // A finite v keeps x finite (x += dt v), so x need not be read here.
    if (!(std::isfinite(v2) && IsFinite(w[i]))) bad = 1;
    max_v2 = std::max(max_v2, v2);
  }
  if (!clumps_.empty() && !clumps_.EndStep(p_, g, dt, num_threads_)) bad = 1;  // sum, kick
  time_ += dt;
  ++step_count_;
  lap(phase_times_.integrate);
  if (config_.sleep.enabled && ++m.sleep_counter >= config_.sleep.check_every) {
    m.sleep_counter = 0;
    UpdateSleep();
    if (!clumps_.empty() && clumps_.SyncSleep(p_, config_.sleep.quiet_checks)) {
      m.active_valid = false;  // a clump sleeps as a unit
      m.busy_valid = false;
    }
    lap(phase_times_.sleep);
  }

  StepStatus status;
  if (bad) status.flags |= kNonFinite;
  if (max_v2 > config_.max_speed * config_.max_speed) status.flags |= kRunawaySpeed;
  if (m.max_overlap > config_.max_overlap_fraction) status.flags |= kExcessiveOverlap;
  if (!status.ok()) Diagnose(&status);
  return status;
}

// ---------------------------------------------------------------------------------------------
// Triangle-mesh walls.

int System::AddMesh(TriangleMesh mesh) {
  Impl& m = *impl_;
  Impl::MeshState ms;
  const int nm = materials_.size();
  ms.constants.resize(nm);
  for (int a = 0; a < nm; ++a)
    ms.constants[a] = MakePairConstants(materials_[a], materials_[mesh.material],
                                        materials_.interaction(a, mesh.material));
  for (const Vec3& v : mesh.vertices) ms.reach = std::max(ms.reach, Norm(v));
  ms.world = mesh.vertices;
  ms.mesh = std::move(mesh);
  m.meshes.push_back(std::move(ms));
  return static_cast<int>(m.meshes.size()) - 1;
}

int System::num_meshes() const { return static_cast<int>(impl_->meshes.size()); }
const TriangleMesh& System::mesh(int k) const { return impl_->meshes[k].mesh; }
const MeshMotion& System::mesh_motion(int k) const { return impl_->meshes[k].motion; }
MeshWrench System::mesh_wrench(int k) const { return impl_->meshes[k].wrench; }

void System::SetMeshMotion(int k, const MeshMotion& motion) {
  Impl::MeshState& ms = impl_->meshes[k];
  ms.motion = motion;
  const Pose& pose = motion.pose;
  for (size_t a = 0; a < ms.mesh.vertices.size(); ++a)
    ms.world[a] = Apply(pose, ms.mesh.vertices[a]);
}

namespace {

// World bounding box of each triangle grown by `margin` (lo at 2e, hi at 2e + 1), and the box
// around them all.
void TriangleBoxes(const std::vector<Vec3>& world, const std::vector<std::array<int32_t, 3>>& tris,
                   double margin, std::vector<Vec3>* box, Vec3* all_lo, Vec3* all_hi) {
  box->resize(2 * tris.size());
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  const Vec3 grow{margin, margin, margin};
  for (size_t e = 0; e < tris.size(); ++e) {
    const Vec3 &a = world[tris[e][0]], &b = world[tris[e][1]], &c = world[tris[e][2]];
    const Vec3 tlo =
        Vec3{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})} -
        grow;
    const Vec3 thi =
        Vec3{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})} +
        grow;
    (*box)[2 * e] = tlo;
    (*box)[2 * e + 1] = thi;
    lo = {std::min(lo.x, tlo.x), std::min(lo.y, tlo.y), std::min(lo.z, tlo.z)};
    hi = {std::max(hi.x, thi.x), std::max(hi.y, thi.y), std::max(hi.z, thi.z)};
  }
  *all_lo = lo;
  *all_hi = hi;
}

// Whether c lies within the box [lo, hi] grown by d.
inline bool InBox(const Vec3& c, const Vec3& lo, const Vec3& hi, double d) {
  return !(c.x < lo.x - d || c.x > hi.x + d || c.y < lo.y - d || c.y > hi.y + d || c.z < lo.z - d ||
           c.z > hi.z + d);
}

}  // namespace

// Candidates of mesh k: every (particle, triangle) pair closer than r + skin now. They stay valid
// while the mesh's largest vertex displacement plus the particles' largest displacement since
// the build stays below the skin (checked in MeshForces).
void System::BuildMeshCandidates(int k) {
  Impl& m = *impl_;
  Impl::MeshState& ms = m.meshes[k];
  const size_t n = p_.size();
  const auto& tris = ms.mesh.triangles;
  const size_t nt = tris.size();
  // World bounding boxes of the triangles and of the whole mesh.
  std::vector<Vec3>& box = m.scratch_v;
  Vec3 mlo, mhi;
  TriangleBoxes(ms.world, tris, 0.0, &box, &mlo, &mhi);
  ms.group_particle.clear();
  ms.group_start.clear();
  ms.cand_tri.clear();
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = p_.x[i];
    const double reach = p_.radius[i] + m.skin;
    if (!InBox(c, mlo, mhi, reach)) continue;
    const size_t first = ms.cand_tri.size();
    for (size_t e = 0; e < nt; ++e) {
      if (!InBox(c, box[2 * e], box[2 * e + 1], reach)) continue;
      const ClosestPoint cp = ClosestPointOnTriangle(c, ms.world[tris[e][0]], ms.world[tris[e][1]],
                                                     ms.world[tris[e][2]]);
      if (Norm2(c - cp.point) < reach * reach) ms.cand_tri.push_back(static_cast<int32_t>(e));
    }
    if (ms.cand_tri.size() > first) {
      ms.group_particle.push_back(static_cast<int32_t>(i));
      ms.group_start.push_back(static_cast<int32_t>(first));
    }
  }
  ms.group_start.push_back(static_cast<int32_t>(ms.cand_tri.size()));
  ms.pose_build = ms.motion.pose;
  ms.particle_drift = 0;
  ms.candidates_valid = true;
}

// Particle-mesh contacts (Hertz-Mindlin, dem/contact.h, with the particle-mesh interaction; the
// mesh is rigid and kinematic, so R* = r and m* = m). A sphere may touch several triangles; to
// count a flat region, a shared edge or a shared vertex once, the touching triangles are taken
// nearest first and a further one is kept only if its closest point lies strictly above the
// tangent plane of every contact kept so far. On a flat or convex patch all closest points lie
// in (or below) that plane and only the nearest counts; in a concave corner the second face
// rises above it and is a second, genuine contact.
void System::MeshForces() {
  Impl& m = *impl_;
  const double dt = config_.time_step;
  constexpr int kMaxHits = 16, kMaxContacts = 4;
  int64_t total = 0;
  double worst_overlap = 0;
  m.mesh_worst = 0;
  m.mesh_worst_id = -1;
  for (int k = 0; k < static_cast<int>(m.meshes.size()); ++k) {
    Impl::MeshState& ms = m.meshes[k];
    const Pose& pose = ms.motion.pose;
    if (ms.candidates_valid) {
      const Quat dq = pose.orientation * Conjugate(ms.pose_build.orientation);
      const double angle =
          2.0 * std::atan2(std::sqrt(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z), std::abs(dq.w));
      const double moved = Norm(pose.position - ms.pose_build.position) + angle * ms.reach;
      if (!(moved + ms.particle_drift < 0.9 * m.skin)) ms.candidates_valid = false;
    }
    if (!ms.candidates_valid) BuildMeshCandidates(k);

    const int ng = static_cast<int>(ms.group_particle.size());
    ms.group_force.resize(ng);
    ms.group_torque.resize(ng);
    ms.group_mesh_torque.resize(ng);
    ms.group_overlap.assign(ng, 0.0);
    ms.group_new.assign(ng, 0);
    ms.group_history.resize(ng + 1);
    ms.fresh.resize(static_cast<size_t>(kMaxContacts) * ng);
    // History of each group (both lists are sorted by particle storage index).
    size_t h = 0;
    for (int g = 0; g < ng; ++g) {
      while (h < ms.history.size() && ms.history[h].index < ms.group_particle[g]) ++h;
      ms.group_history[g] = static_cast<int32_t>(h);
    }
    ms.group_history[ng] = static_cast<int32_t>(ms.history.size());

    const Vec3 origin = pose.position, vel = ms.motion.velocity, omega = ms.motion.angular_velocity;
    const auto& tris = ms.mesh.triangles;
    double worst = 0;
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(max : worst)
    for (int g = 0; g < ng; ++g) {
      const int32_t i = ms.group_particle[g];
      const Vec3 c = p_.x[i];
      const double r = p_.radius[i];
      struct Hit {
        double dist;
        Vec3 point;
        int32_t tri;
      };
      Hit hits[kMaxHits];
      int nh = 0;
      for (int32_t e = ms.group_start[g]; e < ms.group_start[g + 1] && nh < kMaxHits; ++e) {
        const auto& t = tris[ms.cand_tri[e]];
        const ClosestPoint cp =
            ClosestPointOnTriangle(c, ms.world[t[0]], ms.world[t[1]], ms.world[t[2]]);
        const double d2 = Norm2(c - cp.point);
        if (d2 < r * r) hits[nh++] = {std::sqrt(d2), cp.point, ms.cand_tri[e]};
      }
      // Nearest first; ties by triangle index (deterministic).
      std::sort(hits, hits + nh, [](const Hit& a, const Hit& b) {
        return a.dist != b.dist ? a.dist < b.dist : a.tri < b.tri;
      });
      // History entries of this particle (each used once).
      int32_t hb = ms.group_history[g], he = hb;
      while (he < ms.group_history[ng] && ms.history[he].index == i) ++he;
      bool used[kMaxContacts * 2] = {};
      Vec3 fi, ti, tm;
      Vec3 kept_point[kMaxContacts], kept_normal[kMaxContacts];
      int nk = 0;
      for (int a = 0; a < nh && nk < kMaxContacts; ++a) {
        const Hit& hit = hits[a];
        Vec3 out;  // unit normal from the mesh to the particle centre
        if (hit.dist > 1e-9 * r) {
          out = (1.0 / hit.dist) * (c - hit.point);
        } else {  // centre on the surface: the face normal
          const auto& t = tris[hit.tri];
          const Vec3 fn = Cross(ms.world[t[1]] - ms.world[t[0]], ms.world[t[2]] - ms.world[t[0]]);
          out = (1.0 / Norm(fn)) * fn;
        }
        bool covered = false;
        for (int b = 0; b < nk; ++b)
          covered = covered || Dot(hit.point - kept_point[b], kept_normal[b]) <= 1e-9 * r;
        if (covered) continue;
        const Vec3 nrm = -out;  // from the particle to the mesh
        const double delta = r - hit.dist;
        const Vec3 v_mesh = vel + Cross(omega, hit.point - origin);
        const Vec3 v_rel = v_mesh - (p_.v[i] + r * Cross(p_.w[i], nrm));
        const Vec3 w_rel = p_.w[i] - omega;
        // Tangential history: the stored contact of this particle whose normal is closest.
        Vec3 shear;
        int best = -1;
        double best_dot = 0.8;  // within ~37 degrees
        for (int32_t e = hb; e < he && e - hb < kMaxContacts * 2; ++e) {
          const double d = Dot(ms.history[e].normal, nrm);
          if (!used[e - hb] && d > best_dot) {
            best_dot = d;
            best = e;
          }
        }
        if (best >= 0) {
          used[best - hb] = true;
          shear = ms.history[best].shear;
        }
        const ContactForce cf =
            EvaluateContact(ms.constants[p_.material[i]], nrm, delta, r, p_.mass[i], v_rel, w_rel,
                            p_.inv_inertia[i], dt, shear);
        const Vec3 fa = cf.ft - cf.fn * nrm;  // on the particle
        fi += fa;
        ti += r * Cross(nrm, cf.ft) + cf.mr;
        tm += Cross(hit.point - origin, -fa) - cf.mr;
        ms.fresh[static_cast<size_t>(kMaxContacts) * g + nk] = {i, p_.id[i], nrm, shear};
        kept_point[nk] = hit.point;
        kept_normal[nk] = out;
        ++nk;
        worst = std::max(worst, delta / (2.0 * r));
        ms.group_overlap[g] = std::max(ms.group_overlap[g], delta / (2.0 * r));
      }
      ms.group_force[g] = fi;
      ms.group_torque[g] = ti;
      ms.group_mesh_torque[g] = tm;
      ms.group_new[g] = nk;
    }
    // Sums in group order (fixed by the data: deterministic whatever the thread count).
    MeshWrench wrench;
    ms.history.clear();
    for (int g = 0; g < ng; ++g) {
      if (ms.group_new[g] == 0) continue;
      const int32_t i = ms.group_particle[g];
      if (ms.group_overlap[g] > m.mesh_worst) {
        m.mesh_worst = ms.group_overlap[g];
        m.mesh_worst_id = p_.id[i];
        m.mesh_worst_mesh = k;
      }
      p_.f[i] += ms.group_force[g];
      p_.t[i] += ms.group_torque[g];
      wrench.force -= ms.group_force[g];
      wrench.torque += ms.group_mesh_torque[g];
      wrench.contacts += ms.group_new[g];
      for (int a = 0; a < ms.group_new[g]; ++a)
        ms.history.push_back(ms.fresh[static_cast<size_t>(kMaxContacts) * g + a]);
      if (!p_.awake[i]) {  // a mesh touched a sleeping particle: wake it (its pairs are listed)
        p_.awake[i] = 1;
        p_.f[i] = ms.group_force[g];  // at rest in equilibrium but for the mesh's push
        p_.t[i] = ms.group_torque[g];
        m.busy_valid = false;
        m.active_valid = false;
      }
    }
    ms.wrench = wrench;
    total += wrench.contacts;
    worst_overlap = std::max(worst_overlap, worst);
  }
  m.mesh_contacts = total;
  m.max_overlap = std::max(m.max_overlap, worst_overlap);
}

// ---------------------------------------------------------------------------------------------
// Sleeping.

void System::set_sleep(const SleepConfig& sleep) {
  config_.sleep = sleep;
  if (!sleep.enabled) {
    for (size_t i = 0; i < p_.size(); ++i)
      if (!p_.awake[i]) {
        p_.awake[i] = 1;
        p_.f[i] = Vec3{};
        p_.t[i] = Vec3{};
      }
  }
  impl_->needs_rebuild = true;  // the list and the busy particles depend on sleeping
  impl_->active_valid = false;
}

int64_t System::awake_count() const {
  int64_t n = 0;
  for (uint8_t a : p_.awake) n += a != 0;
  return n;
}

// Sleep/wake decisions. `awake` holds 0 for a sleeping particle and 1 + q for an awake one that
// has been quiet (slower than sleep.speed, spinning slower than speed / r) for q checks in a row.
// A sleeper wakes when touched by an awake particle faster than wake_speed, or, once any sleeper
// has entered the inner zone of a mesh (centre closer than wake_distance to its surface), with
// every sleeper of the outer zone (closer than wake_distance + wake_margin). An awake particle
// quiet for quiet_checks checks outside every outer zone sleeps with v = w = 0.
void System::UpdateSleep() {
  Impl& m = *impl_;
  const SleepConfig& sc = config_.sleep;
  const size_t n = p_.size();
  if (!m.list_valid) return;
  FlushNear();  // the wake test reads touching
  std::vector<uint8_t>& woken = m.scratch_wake;
  woken.assign(n, 0);
  const double wake2 = sc.wake_speed * sc.wake_speed;
  // Only a pair with an awake end can wake its other end, and its owner is busy (RefreshBusy).
  // Even slabs, then odd ones: a pair's partner lies in its owner's slab or the next, so no two
  // threads mark the same particle (and marking is an OR: the order does not matter).
  if (!m.busy_valid) RefreshBusy();
  const int ns = m.list.num_slabs();
  for (int phase = 0; phase < 2; ++phase) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(num_threads_)
    for (int sl = phase; sl < ns; sl += 2)
      for (int32_t a = m.slab_busy[sl]; a < m.slab_busy[sl + 1]; ++a) {
        const int32_t i = m.busy[a];
        for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k) {
          if (!m.touching[k]) continue;
          const int32_t j = m.list.partner[k];
          if (!p_.awake[i] && p_.awake[j] && Norm2(p_.v[j]) > wake2) woken[i] = 1;
          if (!p_.awake[j] && p_.awake[i] && Norm2(p_.v[i]) > wake2) woken[j] = 1;
        }
      }
  }
  // Zones around the meshes, by distance from a particle's centre to the mesh surface: inner
  // (< wake_distance) and outer (< wake_distance + wake_margin). Triangles are tested only when
  // their bounding box, grown by the outer distance, holds the centre.
  const double d_in = sc.wake_distance, d_out = sc.wake_distance + sc.wake_margin;
  std::vector<uint8_t>& zone = m.scratch_zone;  // 0 far, 1 outer, 2 inner (n)
  zone.assign(n, 0);
  for (const Impl::MeshState& ms : m.meshes) {
    const auto& tris = ms.mesh.triangles;
    std::vector<Vec3> box;
    Vec3 lo, hi;
    TriangleBoxes(ms.world, tris, d_out, &box, &lo, &hi);
    // Only the slabs that can hold a centre in the box: no particle has moved more than half the
    // skin since the list was built (else it would have been built again this step).
    const Vec3 reach{m.skin, m.skin, m.skin};
    int s0 = 0, s1 = -1;
    m.list.SlabSpan(lo - reach, hi + reach, &s0, &s1);
    const int64_t i0 = m.list.slab_start[s0], i1 = m.list.slab_start[s1 + 1];
#pragma omp parallel for schedule(static) num_threads(num_threads_)
    for (int64_t i = i0; i < i1; ++i) {
      const Vec3 c = p_.x[i];
      if (zone[i] == 2 || !InBox(c, lo, hi, 0.0)) continue;
      double best2 = d_out * d_out;
      for (size_t e = 0; e < tris.size(); ++e) {
        if (!InBox(c, box[2 * e], box[2 * e + 1], 0.0)) continue;
        const ClosestPoint cp = ClosestPointOnTriangle(c, ms.world[tris[e][0]],
                                                       ms.world[tris[e][1]], ms.world[tris[e][2]]);
        best2 = std::min(best2, Norm2(c - cp.point));
        if (best2 < d_in * d_in) break;
      }
      if (best2 < d_in * d_in) {
        zone[i] = 2;
      } else if (best2 < d_out * d_out) {
        zone[i] = std::max<uint8_t>(zone[i], 1);
      }
    }
  }
  // Does a sleeper lie in an inner zone? Then every sleeper of the outer zones wakes.
  const int64_t nn = static_cast<int64_t>(n);
  int batch = 0;
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(| : batch)
  for (int64_t i = 0; i < nn; ++i) batch |= !p_.awake[i] && zone[i] == 2;
  const double quiet2 = sc.speed * sc.speed;
  int woke = 0, slept = 0;
  int64_t awake = 0;
#pragma omp parallel for schedule(static) num_threads(num_threads_) \
    reduction(| : woke, slept) reduction(+ : awake)
  for (int64_t i = 0; i < nn; ++i) {
    const bool near = zone[i] != 0;
    uint8_t& a = p_.awake[i];
    if (a == 0) {
      if ((batch && near) || woken[i]) {
        a = 1;
        p_.f[i] = Vec3{};  // at rest in equilibrium (its force was not kept while asleep)
        p_.t[i] = Vec3{};
        woke = 1;
      }
    } else {
      const double r = p_.radius[i];
      const bool quiet = Norm2(p_.v[i]) < quiet2 && Norm2(p_.w[i]) * r * r < quiet2;
      if (near || !quiet) {
        a = 1;
      } else if (a > sc.quiet_checks) {
        a = 0;
        p_.v[i] = Vec3{};
        p_.w[i] = Vec3{};
        slept = 1;
      } else {
        ++a;
      }
    }
    awake += a != 0;
  }
  m.awake = awake;
  if (woke || slept) {
    m.busy_valid = false;
    m.active_valid = false;
  }
}

void System::RefreshActive() {
  Impl& m = *impl_;
  // The rebuild test scans only the active particles: the sleepers' displacement since the build
  // (frozen while they sleep) is measured here, whoever put them to sleep.
  const bool built = m.list_valid && m.x_build.size() == p_.size();
  const int64_t n = static_cast<int64_t>(p_.size());
  const uint8_t* awake = p_.awake.data();
  // Clumps place their spheres themselves: then any sleeper may have moved.
  const bool tracked = m.moved.size() == p_.size() && clumps_.empty();
  if (!tracked) m.moved.assign(n, 1);
  uint8_t* moved = m.moved.data();
  // Count per chunk, then fill each chunk's run in storage order (chunks: the result does not
  // depend on the thread count).
  const int64_t chunks = 64, per = (n + chunks - 1) / chunks;
  std::vector<int64_t> at(chunks + 1, 0);
  double asleep2 = 0;
#pragma omp parallel for schedule(static) num_threads(num_threads_) reduction(max : asleep2)
  for (int64_t c = 0; c < chunks; ++c) {
    int64_t count = 0;
    for (int64_t i = c * per; i < std::min(n, (c + 1) * per); ++i) {
      if (awake[i]) {
        ++count;
      } else if (built && moved[i]) {
        asleep2 = std::max(asleep2, Norm2(p_.x[i] - m.x_build[i]));
      }
    }
    at[c + 1] = count;
  }
  for (int64_t c = 0; c < chunks; ++c) at[c + 1] += at[c];
  ResizeWithRoom(m.active, at[chunks]);
  int32_t* active = m.active.data();
#pragma omp parallel for schedule(static) num_threads(num_threads_)
  for (int64_t c = 0; c < chunks; ++c) {
    int64_t k = at[c];
    for (int64_t i = c * per; i < std::min(n, (c + 1) * per); ++i)
      if (awake[i]) {
        active[k++] = static_cast<int32_t>(i);
        moved[i] = 1;
      }
  }
  m.asleep_drift = std::sqrt(asleep2);
  m.active_valid = true;
  m.awake = static_cast<int64_t>(m.active.size());
}

void System::Diagnose(StepStatus* status) const {
  // Rare path: find the offending particle with the smallest persistent id and say what to do.
  status->time = time_;
  std::ostringstream msg;
  msg.precision(6);
  const size_t n = p_.size();
  auto first = [&](auto pred) {
    int64_t best = -1;
    size_t at = 0;
    for (size_t i = 0; i < n; ++i)
      if (pred(i) && (best < 0 || p_.id[i] < best)) {
        best = p_.id[i];
        at = i;
      }
    return std::make_pair(best, at);
  };
  if (status->flags & kNonFinite) {
    auto [id, i] = first(
        [&](size_t i) { return !(IsFinite(p_.x[i]) && IsFinite(p_.v[i]) && IsFinite(p_.w[i])); });
    status->particle = id;
    msg << "particle " << id << " has a non-finite position or velocity at t = " << time_
        << " s; lower time_step.rayleigh_fraction";
    (void)i;
  } else if (status->flags & kRunawaySpeed) {
    const double vmax2 = config_.max_speed * config_.max_speed;
    auto [id, i] = first([&](size_t i) { return Norm2(p_.v[i]) > vmax2; });
    status->particle = id;
    msg << "particle " << id << " moves at " << Norm(p_.v[i]) << " m/s at t = " << time_
        << " s, above the runaway limit " << config_.max_speed
        << " m/s; lower time_step.rayleigh_fraction or check restitution <= 1";
  } else {
    // Excessive overlap: find the deepest particle-particle or particle-wall overlap.
    const Impl& m = *impl_;
    double worst = 0;
    int64_t id = -1;
    std::string against;
    auto where = [&](size_t i) {
      std::ostringstream s;
      s.precision(4);
      s << "(radius " << p_.radius[i] << " m at [" << p_.x[i].x << ", " << p_.x[i].y << ", "
        << p_.x[i].z << "] m)";
      return s.str();
    };
    for (size_t i = 0; i + 1 < m.list.start.size(); ++i)
      for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k) {
        const int32_t j = m.list.partner[k];
        const double ov = (p_.radius[i] + p_.radius[j] - Norm(p_.x[j] - p_.x[i])) /
                          (2.0 * std::min(p_.radius[i], p_.radius[j]));
        if (ov > worst) {
          worst = ov;
          const size_t a = p_.id[i] < p_.id[j] ? i : j, b = a == i ? j : i;
          id = p_.id[a];
          against = " " + where(a) + " against particle " + std::to_string(p_.id[b]) + " " +
                    where(b);
        }
      }
    for (size_t e = 0; e < m.wall_i.size(); ++e) {
      const int32_t i = m.wall_i[e];
      const Plane& pl = config_.planes[m.wall_k[e]];
      const double ov = (p_.radius[i] - Dot(p_.x[i] - pl.point, pl.normal)) / (2 * p_.radius[i]);
      if (ov > worst) {
        worst = ov;
        id = p_.id[i];
        against = " " + where(i) + " against wall plane " + std::to_string(m.wall_k[e]);
      }
    }
    if (m.mesh_worst > worst && m.mesh_worst_id >= 0) {
      worst = m.mesh_worst;
      id = m.mesh_worst_id;
      const std::string& name = m.meshes[m.mesh_worst_mesh].mesh.name;
      against = " against mesh '" + (name.empty() ? std::to_string(m.mesh_worst_mesh) : name) +
                "' (a particle pinched by a moving mesh: keep walls a few diameters away from "
                "its path, or lower its speed)";
    }
    status->particle = id;
    msg << "particle " << id << " overlaps by " << 100.0 * worst << "% of its diameter" << against
        << " at t = " << time_ << " s (limit " << 100.0 * config_.max_overlap_fraction
        << "%); lower time_step.rayleigh_fraction or raise the shear modulus";
  }
  status->message = msg.str();
}

// Sums over particles in persistent-id order, so they do not depend on storage order.
template <typename F>
static void ForEachById(const Particles& p, int64_t next_id, F fn) {
  std::vector<int32_t> index(next_id, -1);
  for (size_t i = 0; i < p.size(); ++i) index[p.id[i]] = static_cast<int32_t>(i);
  for (int64_t id = 0; id < next_id; ++id)
    if (index[id] >= 0) fn(static_cast<size_t>(index[id]));
}

double System::KineticEnergy() const {
  double e = 0;
  ForEachById(p_, next_id_, [&](size_t i) {
    if (clumps_.ClumpOf(p_.id[i]) >= 0) return;
    e += 0.5 * p_.mass[i] * Norm2(p_.v[i]) + 0.5 / p_.inv_inertia[i] * Norm2(p_.w[i]);
  });
  return e + clumps_.KineticEnergy();
}

double System::PotentialEnergy() const {
  double e = 0;
  ForEachById(p_, next_id_, [&](size_t i) {
    if (clumps_.ClumpOf(p_.id[i]) < 0) e -= p_.mass[i] * Dot(config_.gravity, p_.x[i]);
  });
  return e + clumps_.PotentialEnergy(config_.gravity);
}

double System::ElasticEnergy() const {
  // Hertz normal potential: integral of 4/3 E* sqrt(R*) d^(3/2) = 8/15 E* sqrt(R*) delta^(5/2).
  const Impl& m = *impl_;
  const int nm = materials_.size();
  double e = 0;
  if (!m.list_valid) return 0;
  for (size_t i = 0; i + 1 < m.list.start.size(); ++i)
    for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k) {
      const int32_t j = m.list.partner[k];
      const double rsum = p_.radius[i] + p_.radius[j];
      const double delta = rsum - Norm(p_.x[j] - p_.x[i]);
      if (delta <= 0) continue;
      const double r_star = p_.radius[i] * p_.radius[j] / rsum;
      const PairConstants& c = m.pair[p_.material[i] * nm + p_.material[j]];
      e += 0.4 * HertzForce(c.e_star, r_star, delta) * delta;
    }
  const int np = static_cast<int>(config_.planes.size());
  for (size_t e_i = 0; e_i < m.wall_i.size(); ++e_i) {
    const int32_t i = m.wall_i[e_i];
    const Plane& pl = config_.planes[m.wall_k[e_i]];
    const double delta = p_.radius[i] - Dot(p_.x[i] - pl.point, pl.normal);
    if (delta <= 0) continue;
    const PairConstants& c = m.wall[p_.material[i] * np + m.wall_k[e_i]];
    e += 0.4 * HertzForce(c.e_star, p_.radius[i], delta) * delta;
  }
  return e;
}

Vec3 System::Momentum() const {
  Vec3 pm;
  ForEachById(p_, next_id_, [&](size_t i) {
    if (clumps_.ClumpOf(p_.id[i]) < 0) pm += p_.mass[i] * p_.v[i];
  });
  return pm + clumps_.Momentum();
}

uint64_t System::StateHash() const {
  // FNV-1a 64 over the bytes of the state, in persistent-id order.
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, size_t bytes) {
    const unsigned char* c = static_cast<const unsigned char*>(data);
    for (size_t k = 0; k < bytes; ++k) {
      h ^= c[k];
      h *= 1099511628211ull;
    }
  };
  ForEachById(p_, next_id_, [&](size_t i) {
    mix(&p_.id[i], sizeof(int64_t));
    mix(&p_.x[i], sizeof(Vec3));
    mix(&p_.v[i], sizeof(Vec3));
    mix(&p_.w[i], sizeof(Vec3));
    mix(&p_.radius[i], sizeof(double));
    mix(&p_.material[i], sizeof(int32_t));
  });
  const Clumps& c = clumps_.state();
  for (size_t k = 0; k < c.size(); ++k) {
    mix(&c.x[k], sizeof(Vec3));
    mix(&c.v[k], sizeof(Vec3));
    mix(&c.q[k], sizeof(Quat));
    mix(&c.l[k], sizeof(Vec3));
  }
  mix(&time_, sizeof(double));
  return h;
}

}  // namespace dem

// The neighbour-list build (Rebuild): storage reordered by cell, the half list and the plane
// candidates made again, and the contact history carried over through the storage permutation.
#include <algorithm>

#include "dem/clump.h"
#include "dem/internal_grow.h"
#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem::internal {

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

// Whether a particle at x with radius r is a candidate of the plane (closer than r + skin).
inline bool NearPlane(const Vec3& x, double r, const Plane& plane, double skin) {
  return Dot(x - plane.point, plane.normal) < r + skin;
}

// 1. Keeps the present list and history (Workspace::old_*): they are carried over to the new list
// through the storage permutation. Returns how many particles the old list covers (list indices
// < n_old have a list; particles added since have none).
int64_t KeepOldList(Workspace& m, bool carry, int nt) {
  if (carry) FlushNear(m, nt);
  m.stale.list_history = false;
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
  return n_old;
}

// 2. Grid sized for the present particles; storage reordered by cell, ties by persistent id. The
// grid spans the particles' bounding box (within the domain), so that every slab holds particles
// and the slabs share the work evenly.
void SortStorage(Workspace& m, Particles& p, const SystemConfig& config, int64_t next_id, int nt) {
  const size_t n = p.size();
  double r_max = 0;
  double lox = config.domain_max.x, loy = config.domain_max.y, loz = config.domain_max.z;
  double hix = config.domain_min.x, hiy = config.domain_min.y, hiz = config.domain_min.z;
  {
    const Vec3* xs = p.x.data();
    const double* rs = p.radius.data();
    const int64_t nn = static_cast<int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max                     \
                                                                    : r_max, hix, hiy, hiz) \
    reduction(min                                                                           \
              : lox, loy, loz)
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
  Vec3 lo{std::max(lox, config.domain_min.x), std::max(loy, config.domain_min.y),
          std::max(loz, config.domain_min.z)};
  Vec3 hi{std::min(hix, config.domain_max.x), std::min(hiy, config.domain_max.y),
          std::min(hiz, config.domain_max.z)};
  if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z)) {
    lo = config.domain_min;
    hi = config.domain_max;
  }
  m.list.SetupGrid(lo, hi, 2 * r_max + m.skin, n);
  m.index_of_id.assign(next_id, -1);
  for (size_t i = 0; i < n; ++i) m.index_of_id[p.id[i]] = static_cast<int32_t>(i);
  m.visit.clear();
  for (int64_t id = 0; id < next_id; ++id)
    if (m.index_of_id[id] >= 0) m.visit.push_back(m.index_of_id[id]);
  m.list.ComputeOrder(p.x.data(), m.visit, &m.perm, nt,
                      config.sleep.enabled ? p.awake.data() : nullptr);
  Permute(p.id, m.perm, m.scratch_i64, nt);
  Permute(p.x, m.perm, m.scratch_v, nt);
  Permute(p.v, m.perm, m.scratch_v, nt);
  Permute(p.w, m.perm, m.scratch_v, nt);
  Permute(p.f, m.perm, m.scratch_v, nt);
  Permute(p.t, m.perm, m.scratch_v, nt);
  Permute(p.radius, m.perm, m.scratch_d, nt);
  Permute(p.mass, m.perm, m.scratch_d, nt);
  Permute(p.inv_mass, m.perm, m.scratch_d, nt);
  Permute(p.inv_inertia, m.perm, m.scratch_d, nt);
  Permute(p.material, m.perm, m.scratch_i32, nt);
  Permute(p.awake, m.perm, m.scratch_u8, nt);
  for (size_t i = 0; i < n; ++i) m.index_of_id[p.id[i]] = static_cast<int32_t>(i);
}

// Notes whether every particle has one material (Workspace::particle_material) and whether all
// are alike (Workspace::alike).
void NoteAlike(Workspace& m, const Particles& p) {
  const size_t n = p.size();
  m.particle_material = n > 0 ? p.material[0] : -1;
  for (size_t i = 1; i < n && m.particle_material >= 0; ++i)
    if (p.material[i] != m.particle_material) m.particle_material = -1;
  Alike& a = m.alike;
  a.all = n > 0;
  if (a.all) {
    a.radius = p.radius[0];
    a.mass = p.mass[0];
    a.inv_mass = p.inv_mass[0];
    a.inv_inertia = p.inv_inertia[0];
  }
  for (size_t i = 1; i < n && a.all; ++i)
    a.all = p.radius[i] == a.radius && p.mass[i] == a.mass && p.inv_mass[i] == a.inv_mass &&
            p.inv_inertia[i] == a.inv_inertia;
}

// Mesh contact history follows its particles; candidates are found again at the next step.
void FollowMeshHistory(Workspace& m, int64_t next_id) {
  for (MeshState& ms : m.meshes) {
    size_t kept = 0;
    for (MeshHistory& h : ms.history) {
      if (h.id >= next_id || m.index_of_id[h.id] < 0) continue;
      h.index = m.index_of_id[h.id];
      ms.history[kept++] = h;
    }
    ms.history.resize(kept);
    std::stable_sort(ms.history.begin(), ms.history.end(),
                     [](const MeshHistory& l, const MeshHistory& r) { return l.index < r.index; });
    ms.candidates_valid = false;
  }
}

// 3. Counts each particle's plane candidates into wall_start and sizes the wall arrays (listed
// with their history by CarryPlaneHistory).
void CountPlaneCandidates(Workspace& m, const Particles& p, const SystemConfig& config, int nt) {
  const size_t n = p.size();
  const int np = static_cast<int>(config.planes.size());
  const Plane* planes = config.planes.data();
  const Vec3* x = p.x.data();
  const double* radius = p.radius.data();
  const double skin = m.skin;
  m.wall_start.resize(n + 1);
  int32_t* wall_start = m.wall_start.data();
  const int64_t nn = static_cast<int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t i = 0; i < nn; ++i) {
    int32_t count = 0;
    for (int k = 0; k < np; ++k) count += NearPlane(x[i], radius[i], planes[k], skin);
    wall_start[i + 1] = count;
  }
  wall_start[0] = 0;
  for (int64_t i = 0; i < nn; ++i) wall_start[i + 1] += wall_start[i];
  ResizeWithRoom(m.wall_i, wall_start[n]);
  ResizeWithRoom(m.wall_k, wall_start[n]);
  ResizeWithRoom(m.wall_shear, wall_start[n]);
}

// 4. Carries the pair history over: a new pair (i, j) was the old pair of perm[i] and perm[j],
// owned by the smaller of the two (its shear flips sign if the owner changed). Only pairs that
// touched with a nonzero spring carry anything; every other pair starts afresh. So the old list
// is walked (in storage order) and each such pair is looked up in the new one: one new pair per
// old pair, so the writes never meet.
void CarryPairHistory(Workspace& m, bool carry, int64_t n_old, int64_t n, int nt) {
  const int64_t num_pairs = static_cast<int64_t>(m.list.num_pairs());
  ResizeWithRoom(m.shear, num_pairs);
  ResizeWithRoom(m.touching, num_pairs);
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  const int32_t* perm = m.perm.data();
  const int32_t* o_start = m.old_start.data();
  const int32_t* o_partner = m.old_partner.data();
  const Vec3* o_shear = m.old_shear.data();
  const uint8_t* o_touching = m.old_touching.data();
  Vec3* shear = m.shear.data();
  uint8_t* touching = m.touching.data();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t k = 0; k < num_pairs; ++k) {
    shear[k] = Vec3{};
    touching[k] = 0;
  }
  if (!carry) return;
  m.new_of_old.resize(n);
  int32_t* new_of_old = m.new_of_old.data();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t i = 0; i < n; ++i) new_of_old[perm[i]] = static_cast<int32_t>(i);
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

// Lists each particle's plane candidates (counted by CountPlaneCandidates), each with the
// history its particle had with that plane before the build.
void CarryPlaneHistory(Workspace& m, const Particles& p, const SystemConfig& config, bool carry,
                       int64_t n_old, int nt) {
  const int64_t n = static_cast<int64_t>(p.size());
  const int np = static_cast<int>(config.planes.size());
  const Plane* planes = config.planes.data();
  const Vec3* x = p.x.data();
  const double* radius = p.radius.data();
  const double skin = m.skin;
  const int32_t* perm = m.perm.data();
  const int32_t* wall_start = m.wall_start.data();
  const int32_t* o_wall_start = m.old_wall_start.data();
  const int32_t* o_wall_k = m.old_wall_k.data();
  const Vec3* o_wall_shear = m.old_wall_shear.data();
  int32_t* wall_i = m.wall_i.data();
  int32_t* wall_k = m.wall_k.data();
  Vec3* wall_shear = m.wall_shear.data();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t i = 0; i < n; ++i) {
    const int32_t oi = perm[i];
    int32_t e = wall_start[i];
    for (int k = 0; k < np; ++k) {
      if (!NearPlane(x[i], radius[i], planes[k], skin)) continue;
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

// 5. Puts the pending history (a restored state, removed particles) on the new entries.
void ApplyPending(Workspace& m, int64_t next_id) {
  for (const ContactRecord& c : m.pending) {
    if (c.a < 0 || c.a >= next_id) continue;
    const int32_t ia = m.index_of_id[c.a];
    if (ia < 0) continue;
    if (c.b >= 0) {
      if (c.b >= next_id || m.index_of_id[c.b] < 0) continue;
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
}

}  // namespace

void Rebuild(Workspace& m, Particles& p, ClumpSet& clumps, const SystemConfig& config,
             int64_t next_id, int nt) {
  const int64_t n = static_cast<int64_t>(p.size());
  const bool carry = !m.stale.list;
  const int64_t n_old = KeepOldList(m, carry, nt);
  SortStorage(m, p, config, next_id, nt);
  NoteAlike(m, p);
  FollowMeshHistory(m, next_id);
  // 3. Particle pairs and particle-plane candidates within reach (+ skin). With sleeping, the
  // pairs of two sleepers stay listed (the force pass skips them and keeps their history), so
  // that a particle that wakes needs no rebuild: its pairs are already there.
  const int32_t* clump_of = clumps.Reindex(p, next_id);  // no pairs within a clump
  m.list.Build(p.x.data(), p.radius.data(), p.size(), m.skin, nt, clump_of);
  CountPlaneCandidates(m, p, config, nt);
  CarryPairHistory(m, carry, n_old, n, nt);
  CarryPlaneHistory(m, p, config, carry, n_old, nt);
  ApplyPending(m, next_id);
  // The drift since the build starts from here.
  m.x_build.resize(n);
  {
    const Vec3* x = p.x.data();
    Vec3* xb = m.x_build.data();
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = 0; i < n; ++i) xb[i] = x[i];
  }
  m.drift_bound = 0;
  m.asleep_drift = 0;
  m.moved.assign(n, 0);  // RefreshActive marks the particles it lets move
  m.stale.list = false;
  m.stale.rebuild = false;
  m.stale.active = true;
  m.stale.spins = true;  // the storage was reordered
  m.stale.busy = true;
  m.stale.near = true;
  m.stale.walls = true;
  // The arrays the force pass reads at random, on 2 MB pages where the system allows it.
  for (const auto* a : {&p.x, &p.v, &p.w, &p.f, &p.t, &m.shear, &m.x_build}) AdviseHugePages(*a);
  for (const auto* a : {&p.radius, &p.mass, &p.inv_mass, &p.inv_inertia}) AdviseHugePages(*a);
  for (const auto* a : {&m.list.start, &m.list.partner, &p.material}) AdviseHugePages(*a);
}

}  // namespace dem::internal

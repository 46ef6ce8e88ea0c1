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

// Calls f(array, scratch) for each of the per-particle arrays (all in storage order), with a
// scratch array of its type.
template <typename F>
void ForEachArray(Particles& p, Workspace& m, F f) {
  f(p.id, m.scratch_i64);
  for (auto* v : {&p.x, &p.v, &p.w, &p.f, &p.t}) f(*v, m.scratch_v);
  for (auto* v : {&p.radius, &p.mass, &p.inv_mass, &p.inv_inertia}) f(*v, m.scratch_d);
  f(p.material, m.scratch_i32);
  f(p.awake, m.scratch_u8);
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

// The box the cell grid spans and the cutoff it is made for: the particles' bounding box within
// the domain (or the domain, for no box), so that every slab holds particles and the slabs share
// the work evenly. While a scoop digs into a sleeping bed it often stays the same from one build
// to the next: then only the slabs that particles entered or left are made again (RebuildPart).
struct GridBox {
  Vec3 lo, hi;
  double cutoff = 0;  // 2 r_max + skin [m]
};

GridBox FindGridBox(const Workspace& m, const Particles& p, const SystemConfig& config, int nt) {
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
  GridBox box;
  box.cutoff = 2 * r_max + m.skin;
  box.lo = {std::max(lox, config.domain_min.x), std::max(loy, config.domain_min.y),
            std::max(loz, config.domain_min.z)};
  box.hi = {std::min(hix, config.domain_max.x), std::min(hiy, config.domain_max.y),
            std::min(hiz, config.domain_max.z)};
  if (!(box.hi.x > box.lo.x && box.hi.y > box.lo.y && box.hi.z > box.lo.z)) {
    box.lo = config.domain_min;
    box.hi = config.domain_max;
  }
  return box;
}

// 2. Grid over `box`; storage reordered by cell, ties by persistent id.
void SortStorage(Workspace& m, Particles& p, const SystemConfig& config, const GridBox& box,
                 int64_t next_id, int nt) {
  const size_t n = p.size();
  m.list.SetupGrid(box.lo, box.hi, box.cutoff, n);
  m.index_of_id.assign(next_id, -1);
  for (size_t i = 0; i < n; ++i) m.index_of_id[p.id[i]] = static_cast<int32_t>(i);
  m.visit.clear();
  for (int64_t id = 0; id < next_id; ++id)
    if (m.index_of_id[id] >= 0) m.visit.push_back(m.index_of_id[id]);
  m.list.ComputeOrder(p.x.data(), m.visit, &m.perm, nt,
                      config.sleep.enabled ? p.awake.data() : nullptr);
  ForEachArray(p, m, [&](auto& a, auto& scratch) { Permute(a, m.perm, scratch, nt); });
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

// Puts one pair's history on its slot in the list: the pair of storage indices a and b, listed
// under the smaller, with its shear as seen from a (negated when b owns the slot). A pair the
// list no longer holds (the two moved out of reach) gets nothing.
inline void PutPairHistory(const int32_t* start, const int32_t* partner, int32_t a, int32_t b,
                           const Vec3& shear_a, Vec3* shear, uint8_t* touching) {
  const int32_t owner = std::min(a, b), other = std::max(a, b);
  for (int32_t k = start[owner]; k < start[owner + 1]; ++k)
    if (partner[k] == other) {
      shear[k] = owner == a ? shear_a : -shear_a;
      touching[k] = 1;
      return;
    }
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
      PutPairHistory(start, partner, new_of_old[oi], new_of_old[o_partner[q]], o_shear[q], shear,
                     touching);
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
      PutPairHistory(m.list.start.data(), m.list.partner.data(), ia, m.index_of_id[c.b], c.shear,
                     m.shear.data(), m.touching.data());
    } else {
      const int32_t plane = static_cast<int32_t>(-1 - c.b);
      for (int32_t e = m.wall_start[ia]; e < m.wall_start[ia + 1]; ++e)
        if (m.wall_k[e] == plane) m.wall_shear[e] = c.shear;
    }
  }
  m.pending.clear();
}

// Permute for positions [a, b) only (perm maps those into [a, b)).
template <typename T>
void PermuteRange(std::vector<T>& v, const int32_t* perm, int32_t a, int32_t b,
                  std::vector<T>& scratch) {
  scratch.resize(static_cast<size_t>(b - a));
  for (int32_t i = a; i < b; ++i) scratch[i - a] = v[perm[i]];
  std::copy(scratch.begin(), scratch.end(), v.begin() + a);
}

// The build for a bed of which only parts moved (with sleeping, a dig: ~7% of the paper bed,
// while a full build walks all of it). A particle that no step has moved since the last build
// (Workspace::moved) sits where it was, with its sort key. So when the grid is the same
// (FindGridBox), only the slabs that hold a moved particle, before or after, change their order:
// runs of such slabs (a moved particle's old and new slab in one run) are sorted again, each
// among itself, and the list is made again for each run's slabs and the slab before it (whose
// pairs reach into the run). Every other slab keeps its order, its pairs and their history; the
// pair arrays after a run are shifted by the change in its pair count. The result is the full
// build's, bit for bit (PartialRebuildTest): the same order, the same pairs in the same places,
// the same history (a pair of two unmoved particles was never in a near list since the last
// build, so its history is still as that build left it). On another grid with the same slabs
// (the box's top rose or fell: NeighborList::Regrid) the unmoved slabs whose order the new
// cells change are made again too. Returns false, changing nothing the full build reads, where
// it does not apply (history to apply; other slabs; most of the bed moved).
struct SlabRun {
  int s0, s1;     // its slabs
  int32_t a, b;   // its storage positions [a, b)
  size_t visit0;  // its particles' first entry in Workspace::visit
};
constexpr int kMaxRuns = 16;  // more are merged (each shifts the pair arrays after it once)

bool RebuildPart(Workspace& m, Particles& p, ClumpSet& clumps, const SystemConfig& config,
                 const GridBox& box, int64_t next_id, int nt) {
  const int64_t n = static_cast<int64_t>(p.size());
  if (!config.partial_rebuild || !config.sleep.enabled || m.stale.list || m.stale.rebuild ||
      !m.pending.empty() || m.moved.size() != p.size() || m.x_build.size() != p.size() ||
      m.list.start.size() != p.size() + 1 || m.index_of_id.size() != static_cast<size_t>(next_id))
    return false;
  // Another grid (the bounding box grew or shrank across the slabs, as when a particle flies up
  // out of the bed and lands again) with the same slabs: every particle's key on it, and the
  // slabs whose unmoved particles no longer lie in its order made again too.
  const bool regrid = !m.list.SameGrid(box.lo, box.hi, box.cutoff, p.size());
  const int ns = m.list.num_slabs();
  m.build_slab_start = m.list.slab_start;  // the storage slabs (Regrid counts them anew)
  const int32_t* slab_start = m.build_slab_start.data();
  const uint8_t* moved = m.moved.data();
  const Vec3* x = p.x.data();
  if (regrid &&
      !m.list.Regrid(box.lo, box.hi, box.cutoff, p.size(), x, p.awake.data(), &m.regrid_key, nt))
    return false;
  // The slabs the moved particles were in at the build (their storage slab) or are in now, and
  // every slab between the two.
  std::vector<int32_t> reach(ns, -1);  // the last slab a run starting here must take in
  const int64_t* key = m.regrid_key.data();
  const int64_t* id = p.id.data();
  for (int s = 0; s < ns; ++s) {
    for (int32_t i = slab_start[s]; i < slab_start[s + 1]; ++i) {
      if (!moved[i] && !regrid) continue;
      const int now = regrid ? m.list.SlabOfKey(key[i]) : m.list.SlabOf(x[i]);
      if (!moved[i] && now == s) continue;
      const int lo = std::min(s, now);
      reach[lo] = std::max(reach[lo], std::max(s, now));
    }
    if (!regrid || reach[s] >= s) continue;
    // A slab no particle entered or left keeps its order if its keys on the new grid (ties by
    // persistent id, as ComputeOrder orders them) still ascend.
    for (int32_t i = slab_start[s] + 1; i < slab_start[s + 1]; ++i)
      if (key[i] < key[i - 1] || (key[i] == key[i - 1] && id[i] < id[i - 1])) {
        reach[s] = s;
        break;
      }
  }
  // Runs: dirty slabs joined; a gap of one clean slab joins too (that slab's list is made again
  // anyway, as the one before the next run).
  std::vector<SlabRun> runs;
  for (int s = 0; s < ns; ++s) {
    if (reach[s] < 0) continue;
    if (!runs.empty() && s <= runs.back().s1 + 2) {
      runs.back().s1 = std::max(runs.back().s1, reach[s]);
    } else {
      runs.push_back({s, reach[s], 0, 0, 0});
    }
  }
  if (runs.empty()) return false;
  while (runs.size() > kMaxRuns) {  // join the two runs closest together
    size_t k = 1;
    for (size_t r = 2; r < runs.size(); ++r)
      if (runs[r].s0 - runs[r - 1].s1 < runs[k].s0 - runs[k - 1].s1) k = r;
    runs[k - 1].s1 = runs[k].s1;
    runs.erase(runs.begin() + static_cast<std::ptrdiff_t>(k));
  }
  int64_t part = 0;
  for (SlabRun& r : runs) {
    r.a = slab_start[r.s0];
    r.b = slab_start[r.s1 + 1];
    part += r.b - r.a;
  }
  if (10 * part > 8 * n) return false;    // most of the bed: build it all
  slab_start = m.list.slab_start.data();  // (the same at the runs' ends; made again within them)
  // Each run's particles in persistent-id order, one run after the other in `visit`.
  const int32_t* index_of_id = m.index_of_id.data();
  {
    std::vector<size_t> fill(runs.size());
    size_t at = 0;
    for (size_t r = 0; r < runs.size(); ++r) {
      runs[r].visit0 = fill[r] = at;
      at += static_cast<size_t>(runs[r].b - runs[r].a);
    }
    m.visit.resize(at);
    for (int64_t id = 0; id < next_id; ++id) {
      const int32_t i = index_of_id[id];
      if (i < 0) continue;
      const auto r = std::upper_bound(runs.begin(), runs.end(), i,
                                      [](int32_t v, const SlabRun& run) { return v < run.a; });
      if (r == runs.begin() || i >= (r - 1)->b) continue;
      m.visit[fill[r - 1 - runs.begin()]++] = i;
    }
  }
  // Their new order (perm[new] = old; the identity outside the runs).
  m.perm.resize(n);
  int32_t* perm = m.perm.data();
  std::vector<int32_t> run_visit;
  for (const SlabRun& r : runs) {
    run_visit.assign(m.visit.begin() + r.visit0, m.visit.begin() + (r.visit0 + (r.b - r.a)));
    if (!m.list.ComputeOrderSlabs(x, run_visit, r.s0, r.s1, perm + r.a, p.awake.data()))
      return false;  // (the full build makes the grid's starts again)
  }
  // From here on the build goes through. The near slots' history back into the list's arrays.
  FlushNear(m, nt);
  m.stale.list_history = false;
  m.new_of_old.resize(n);
  int32_t* new_of_old = m.new_of_old.data();
  {
    int32_t i = 0;
    for (const SlabRun& r : runs) {
      for (; i < r.a; ++i) perm[i] = new_of_old[i] = i;
      i = r.b;
    }
    for (; i < n; ++i) perm[i] = new_of_old[i] = i;
  }
  for (const SlabRun& r : runs) {
    ForEachArray(p, m, [&](auto& v, auto& scratch) { PermuteRange(v, perm, r.a, r.b, scratch); });
    for (int32_t i = r.a; i < r.b; ++i) {
      m.index_of_id[p.id[i]] = i;
      new_of_old[perm[i]] = i;
    }
  }
  FollowMeshHistory(m, next_id);
  const int32_t* clump_of = clumps.Reindex(p, next_id);  // no pairs within a clump

  // Each run's list (its slabs and the one before) made again, and the pair arrays written anew
  // in one sweep into the spare ones (old_*): the pairs between runs copied, each run's new ones
  // in its place. Then each run's history carried over from the old arrays as CarryPairHistory
  // carries it, and the arrays swapped.
  std::vector<int32_t>& start = m.list.start;
  const std::vector<int32_t>& partner = m.list.partner;
  const size_t num_runs = runs.size();
  std::vector<int32_t> p0(num_runs), p1(num_runs), first(num_runs), old_at(num_runs + 1, 0);
  std::vector<int64_t> mid(num_runs, 0);
  int64_t total = static_cast<int64_t>(partner.size());
  for (size_t k = 0; k < num_runs; ++k) {
    const int L0 = std::max(runs[k].s0 - 1, 0), L1 = runs[k].s1;
    first[k] = slab_start[L0];
    p0[k] = start[first[k]];
    p1[k] = start[runs[k].b];
    old_at[k + 1] = old_at[k] + (runs[k].b - first[k]) + 1;
    m.list.BuildSlabs(p.x.data(), p.radius.data(), m.skin, nt, clump_of, L0, L1);
    for (int s = L0; s <= L1; ++s) mid[k] += static_cast<int64_t>(m.list.slab_pairs(s).size());
    total += mid[k] - (p1[k] - p0[k]);
  }
  m.old_start.resize(old_at[num_runs]);  // each run's old starts, relative to its p0
  for (size_t k = 0; k < num_runs; ++k)
    for (int32_t i = first[k]; i <= runs[k].b; ++i)
      m.old_start[old_at[k] + (i - first[k])] = start[i] - p0[k];
  ResizeWithRoom(m.old_partner, total);
  ResizeWithRoom(m.old_shear, total);
  ResizeWithRoom(m.old_touching, total);
  {
    int32_t from = 0, to = 0, i = 0;  // old and new pair positions, and the next particle
    const auto copy_until = [&](int32_t old_end, int32_t particle_end) {
      std::copy(partner.begin() + from, partner.begin() + old_end, m.old_partner.begin() + to);
      std::copy(m.shear.begin() + from, m.shear.begin() + old_end, m.old_shear.begin() + to);
      std::copy(m.touching.begin() + from, m.touching.begin() + old_end,
                m.old_touching.begin() + to);
      for (; i < particle_end; ++i) start[i] += to - from;
      to += old_end - from;
      from = old_end;
    };
    for (size_t k = 0; k < num_runs; ++k) {
      copy_until(p0[k], first[k]);
      const int L0 = std::max(runs[k].s0 - 1, 0), L1 = runs[k].s1;
      for (int s = L0; s <= L1; ++s) {
        const std::vector<int32_t>& pairs = m.list.slab_pairs(s);
        const std::vector<int32_t>& counts = m.list.slab_counts(s);
        std::copy(pairs.begin(), pairs.end(), m.old_partner.begin() + to);
        for (i = slab_start[s]; i < slab_start[s + 1]; ++i) {
          start[i] = to;
          to += counts[i - slab_start[s]];
        }
      }
      std::fill(m.old_shear.begin() + (to - mid[k]), m.old_shear.begin() + to, Vec3{});
      std::fill(m.old_touching.begin() + (to - mid[k]), m.old_touching.begin() + to, uint8_t{0});
      from = p1[k];
    }
    copy_until(static_cast<int32_t>(partner.size()), static_cast<int32_t>(n + 1));
  }
  for (size_t k = 0; k < num_runs; ++k) {
    const int32_t* o_start = m.old_start.data() + old_at[k];
    const int32_t* o_partner = partner.data() + p0[k];
    const Vec3* o_shear = m.shear.data() + p0[k];
    const uint8_t* o_touching = m.touching.data() + p0[k];
    const int32_t* st = start.data();
    const int32_t* pt = m.old_partner.data();
    Vec3* shear = m.old_shear.data();
    uint8_t* touching = m.old_touching.data();
    const int32_t a_list = first[k];
    const int64_t count = runs[k].b - a_list;
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t r = 0; r < count; ++r)
      for (int32_t q = o_start[r]; q < o_start[r + 1]; ++q) {
        if (!(o_touching[q] && Norm2(o_shear[q]) > 0.0)) continue;
        PutPairHistory(st, pt, new_of_old[a_list + r], new_of_old[o_partner[q]], o_shear[q], shear,
                       touching);
      }
  }
  m.list.partner.swap(m.old_partner);
  m.shear.swap(m.old_shear);
  m.touching.swap(m.old_touching);
  // The plane candidates, as the full build makes them (perm is the identity outside the runs).
  m.old_wall_start.swap(m.wall_start);
  m.old_wall_k.swap(m.wall_k);
  m.old_wall_shear.swap(m.wall_shear);
  CountPlaneCandidates(m, p, config, nt);
  CarryPlaneHistory(m, p, config, true, n, nt);
  // The drift since the build: only the runs' particles moved.
  for (const SlabRun& r : runs)
    std::copy(p.x.begin() + r.a, p.x.begin() + r.b, m.x_build.begin() + r.a);
  ++m.partial_builds;
  return true;
}

}  // namespace

void Rebuild(Workspace& m, Particles& p, ClumpSet& clumps, const SystemConfig& config,
             int64_t next_id, int nt) {
  const int64_t n = static_cast<int64_t>(p.size());
  const GridBox box = FindGridBox(m, p, config, nt);
  if (!RebuildPart(m, p, clumps, config, box, next_id, nt)) {
    const bool carry = !m.stale.list;
    const int64_t n_old = KeepOldList(m, carry, nt);
    SortStorage(m, p, config, box, next_id, nt);
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

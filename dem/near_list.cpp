// The lists the force pass walks, made between neighbour-list builds: the busy particles (with
// sleeping), the near list (the list pairs that can touch soon, holding their history) and the
// visited particles with plane candidates.
#include <algorithm>

#include "dem/internal_grow.h"
#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem::internal {

void FlushNear(Workspace& m, int num_threads) {
  if (!m.stale.list_history) return;
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

void RefreshBusy(Workspace& m, const Particles& p, int nt) {
  const uint8_t* awake = p.awake.data();
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  const int32_t* wall_start = m.wall_start.data();
  const int ns = m.list.num_slabs();
  const int64_t n = static_cast<int64_t>(p.size());
  // Mark, count per slab, then list in storage order (each step in parallel; the result depends
  // on the data only).
  std::vector<uint8_t>& flag = m.scratch_busy;
  flag.resize(n);
  // A pair's partner lies in its owner's slab or the next, so a slab is busy-free when neither
  // it nor the next holds an awake particle: its lists need not be read (most slabs of a
  // sleeping bed).
  std::vector<uint8_t>& slab_awake = m.scratch_slab_awake;
  slab_awake.assign(ns + 1, 0);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int sl = 0; sl < ns; ++sl)
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i)
      if (awake[i]) {
        slab_awake[sl] = 1;
        break;
      }
#pragma omp parallel for schedule(dynamic, 4) num_threads(nt)
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
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int sl = 0; sl < ns; ++sl) {
    int32_t count = 0;
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i) count += flag[i];
    m.slab_busy[sl + 1] = count;
  }
  for (int sl = 0; sl < ns; ++sl) m.slab_busy[sl + 1] += m.slab_busy[sl];
  ResizeWithRoom(m.busy, m.slab_busy[ns]);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int sl = 0; sl < ns; ++sl) {
    int32_t at = m.slab_busy[sl];
    for (int32_t i = m.list.slab_start[sl]; i < m.list.slab_start[sl + 1]; ++i)
      if (flag[i]) m.busy[at++] = i;
  }
  m.stale.busy = false;
  m.stale.near = true;   // the near list covers the busy particles only
  m.stale.walls = true;  // and so does the wall list
}

void ListWallVisits(Workspace& m, bool compact, int nt) {
  const int ns = m.list.num_slabs();
  const int32_t* wall_start = m.wall_start.data();
  const int32_t* busy = m.busy.data();
  m.slab_wall_visit.assign(ns + 1, 0);
  // Count per slab, then list in visiting order (each in parallel; the result depends on the
  // data only).
#pragma omp parallel for schedule(static) num_threads(nt)
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
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int sl = 0; sl < ns; ++sl) {
    const int32_t lo = compact ? m.slab_busy[sl] : m.list.slab_start[sl];
    const int32_t hi = compact ? m.slab_busy[sl + 1] : m.list.slab_start[sl + 1];
    int32_t out = m.slab_wall_visit[sl];
    for (int32_t at = lo; at < hi; ++at) {
      const int32_t i = compact ? busy[at] : at;
      if (wall_start[i + 1] > wall_start[i]) m.wall_visit[out++] = i;
    }
  }
  m.stale.walls = false;
}

namespace {

// 1. The near pairs of each visited particle, at the front of its list range (list pair indices
// into scratch_near_k, their count into near_count).
void FindNearPairs(Workspace& m, const Particles& p, bool sleeping, int nt) {
  const Vec3* x = p.x.data();
  const double* radius = p.radius.data();
  const uint8_t* awake = p.awake.data();
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  int32_t* sparse_k = m.scratch_near_k.data();
  int32_t* near_count = m.near_count.data();
  uint8_t* touched = m.touching.data();
  const double s = m.near_skin;
  // With sleeping, only the particles the force pass visits (RefreshBusy makes the list again
  // when that set changes).
  const int32_t* busy = m.busy.data();
  const int64_t visits = static_cast<int64_t>(sleeping ? m.busy.size() : p.size());
#pragma omp parallel for schedule(static) num_threads(nt)
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
}

// 2. Places each visited particle's slots (near_off), slab after slab in visiting order, and
// weighs each slab's work for the force pass (slab_weight: its slots and its particles). Returns
// the number of slots.
int64_t PlaceSlots(Workspace& m, bool sleeping) {
  const int ns = m.list.num_slabs();
  const int32_t* busy = m.busy.data();
  const int32_t* near_count = m.near_count.data();
  int32_t* near_off = m.near_off.data();
  m.slab_weight.assign(ns, 0);
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
    m.slab_weight[sl] = slots - before + (hi - lo);
  }
  return slots;
}

// 3. Fills the slots, each with its pair's history.
void PackSlots(Workspace& m, int64_t visits, bool sleeping, int nt) {
  const int32_t* busy = m.busy.data();
  const int32_t* start = m.list.start.data();
  const int32_t* partner = m.list.partner.data();
  const int32_t* sparse_k = m.scratch_near_k.data();
  const int32_t* near_count = m.near_count.data();
  const int32_t* near_off = m.near_off.data();
  const uint8_t* touched = m.touching.data();
  const Vec3* shear = m.shear.data();
  int32_t* near_k = m.near_k.data();
  int32_t* near_j = m.near_j.data();
  Vec3* near_shear = m.near_shear.data();
  uint8_t* near_touch = m.near_touch.data();
#pragma omp parallel for schedule(static) num_threads(nt)
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
}

}  // namespace

void BuildNear(Workspace& m, const Particles& p, bool sleeping, int nt) {
  FlushNear(m, nt);  // the old slots' history first: the new slots take it from the list's arrays
  const size_t n = p.size();
  ResizeWithRoom(m.scratch_near_k, m.list.num_pairs());
  m.near_count.resize(n);
  m.near_off.resize(n);
  FindNearPairs(m, p, sleeping, nt);
  const int64_t slots = PlaceSlots(m, sleeping);
  ResizeWithRoom(m.near_k, slots);
  ResizeWithRoom(m.near_j, slots);
  ResizeWithRoom(m.near_shear, slots);
  ResizeWithRoom(m.near_touch, slots);
  const int64_t visits = sleeping ? static_cast<int64_t>(m.busy.size()) : static_cast<int64_t>(n);
  PackSlots(m, visits, sleeping, nt);
  m.near_pairs = slots;
  ListSlotOwners(m, p, sleeping, nt);
  m.stale.list_history = true;
  m.near_bound = 0;
  m.stale.near = false;
  ++m.near_builds;
}

void ListSlotOwners(Workspace& m, const Particles& p, bool sleeping, int nt) {
  const int ns = m.list.num_slabs();
  const int32_t* busy = m.busy.data();
  const int32_t* near_off = m.near_off.data();
  const int32_t* near_count = m.near_count.data();
  // Slots lie slab after slab in visiting order (PlaceSlots): a slab's start is its first
  // visited particle's first slot, or the previous slab's end for a slab with none.
  m.slab_slot.resize(ns + 1);
  int32_t at = 0;
  for (int sl = 0; sl < ns; ++sl) {
    const int64_t lo = sleeping ? m.slab_busy[sl] : m.list.slab_start[sl];
    const int64_t hi = sleeping ? m.slab_busy[sl + 1] : m.list.slab_start[sl + 1];
    m.slab_slot[sl] = at;
    if (hi > lo) {
      const int64_t last = sleeping ? busy[hi - 1] : hi - 1;
      at = near_off[last] + near_count[last];
    }
  }
  m.slab_slot[ns] = at;
  ResizeWithRoom(m.near_i, m.near_pairs);
  int32_t* near_i = m.near_i.data();
  const int64_t visits =
      sleeping ? static_cast<int64_t>(m.busy.size()) : static_cast<int64_t>(p.size());
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t a = 0; a < visits; ++a) {
    const int32_t i = static_cast<int32_t>(sleeping ? busy[a] : a);
    for (int32_t q = near_off[i]; q < near_off[i] + near_count[i]; ++q) near_i[q] = i;
  }
  m.near_owners = true;
}

}  // namespace dem::internal

// Sleeping (SystemConfig::sleep): the sleep and wake decisions, taken every check_every steps
// from the data alone, and the list of the awake particles that the integrator moves.
#include <algorithm>
#include <cmath>

#include "dem/internal_grow.h"
#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"
#include "dem/triangle.h"

namespace dem::internal {

void WakeAll(Particles& p) {
  for (size_t i = 0; i < p.size(); ++i)
    if (!p.awake[i]) {
      p.awake[i] = 1;
      p.f[i] = Vec3{};
      p.t[i] = Vec3{};
    }
}

namespace {

// Marks in `woken` (N) every sleeper touched by an awake particle faster than wake_speed. Only a
// pair with an awake end can wake its other end, and its owner is busy (RefreshBusy). Even slabs,
// then odd ones: a pair's partner lies in its owner's slab or the next, so no two threads mark
// the same particle (and marking is an OR: the order does not matter).
void MarkTouchWakes(Workspace& m, const Particles& p, double wake_speed, int nt,
                    std::vector<uint8_t>* woken) {
  woken->assign(p.size(), 0);
  const double wake2 = wake_speed * wake_speed;
  if (m.stale.busy) RefreshBusy(m, p, nt);
  const int ns = m.list.num_slabs();
  uint8_t* mark = woken->data();
  for (int phase = 0; phase < 2; ++phase) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
    for (int sl = phase; sl < ns; sl += 2)
      for (int32_t a = m.slab_busy[sl]; a < m.slab_busy[sl + 1]; ++a) {
        const int32_t i = m.busy[a];
        for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k) {
          if (!m.touching[k]) continue;
          const int32_t j = m.list.partner[k];
          if (!p.awake[i] && p.awake[j] && Norm2(p.v[j]) > wake2) mark[i] = 1;
          if (!p.awake[j] && p.awake[i] && Norm2(p.v[i]) > wake2) mark[j] = 1;
        }
      }
  }
}

// Zones around the meshes, by distance from a particle's centre to the mesh surface, into `zone`
// (N): 2 inner (< wake_distance), 1 outer (< wake_distance + wake_margin), 0 far. Triangles are
// tested only when their bounding box, grown by the outer distance, holds the centre.
void MarkMeshZones(const Workspace& m, const Particles& p, const SleepConfig& sc, int nt,
                   std::vector<uint8_t>* zone_out) {
  const double d_in = sc.wake_distance, d_out = sc.wake_distance + sc.wake_margin;
  std::vector<uint8_t>& zone = *zone_out;
  zone.assign(p.size(), 0);
  for (const MeshState& ms : m.meshes) {
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
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = i0; i < i1; ++i) {
      const Vec3 c = p.x[i];
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
}

// Applies the decisions (see UpdateSleep) to p.awake; marks the lists stale when any particle
// woke or fell asleep.
void ApplySleepDecisions(Workspace& m, Particles& p, const SleepConfig& sc, int nt) {
  const std::vector<uint8_t>& woken = m.scratch_wake;
  const std::vector<uint8_t>& zone = m.scratch_zone;
  // Does a sleeper lie in an inner zone? Then every sleeper of the outer zones wakes.
  const int64_t nn = static_cast<int64_t>(p.size());
  int batch = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(| : batch)
  for (int64_t i = 0; i < nn; ++i) batch |= !p.awake[i] && zone[i] == 2;
  const double quiet2 = sc.speed * sc.speed;
  int woke = 0, slept = 0;
  int64_t awake = 0;
#pragma omp parallel for schedule(static) num_threads(nt) \
    reduction(| : woke, slept) reduction(+ : awake)
  for (int64_t i = 0; i < nn; ++i) {
    const bool near = zone[i] != 0;
    uint8_t& a = p.awake[i];
    if (a == 0) {
      if ((batch && near) || woken[i]) {
        a = 1;
        p.f[i] = Vec3{};  // at rest in equilibrium (its force was not kept while asleep)
        p.t[i] = Vec3{};
        woke = 1;
      }
    } else {
      const double r = p.radius[i];
      const bool quiet = Norm2(p.v[i]) < quiet2 && Norm2(p.w[i]) * r * r < quiet2;
      if (near || !quiet) {
        a = 1;
      } else if (a > sc.quiet_checks) {
        a = 0;
        p.v[i] = Vec3{};
        p.w[i] = Vec3{};
        if (i < static_cast<int64_t>(m.inv_spin.size())) m.inv_spin[i] = 0;  // with the spin
        slept = 1;
      } else {
        ++a;
      }
    }
    awake += a != 0;
  }
  m.awake = awake;
  if (woke || slept) {
    m.stale.busy = true;
    m.stale.active = true;
  }
}

}  // namespace

// Sleep/wake decisions. `awake` holds 0 for a sleeping particle and 1 + q for an awake one that
// has been quiet (slower than sleep.speed, spinning slower than speed / r) for q checks in a row.
// A sleeper wakes when touched by an awake particle faster than wake_speed, or, once any sleeper
// has entered the inner zone of a mesh (centre closer than wake_distance to its surface), with
// every sleeper of the outer zone (closer than wake_distance + wake_margin). An awake particle
// quiet for quiet_checks checks outside every outer zone sleeps with v = w = 0.
void UpdateSleep(Workspace& m, Particles& p, const SleepConfig& sc, int nt) {
  if (m.stale.list) return;
  FlushNear(m, nt);  // the wake test reads touching
  MarkTouchWakes(m, p, sc.wake_speed, nt, &m.scratch_wake);
  MarkMeshZones(m, p, sc, nt, &m.scratch_zone);
  ApplySleepDecisions(m, p, sc, nt);
}

void RefreshActive(Workspace& m, const Particles& p, int nt) {
  // The rebuild test scans only the active particles: the sleepers' displacement since the build
  // (frozen while they sleep) is measured here, whoever put them to sleep.
  const bool built = !m.stale.list && m.x_build.size() == p.size();
  const int64_t n = static_cast<int64_t>(p.size());
  const uint8_t* awake = p.awake.data();
  // Clumps place their spheres themselves, but only an awake clump's, whose spheres are all awake
  // whenever the active list is made (SyncSleep puts a clump to sleep whole or keeps every sphere
  // awake) or were marked when it woke (ClumpSet::BeginStep, before this list is made again).
  const bool tracked = m.moved.size() == p.size();
  if (!tracked) m.moved.assign(n, 1);
  uint8_t* moved = m.moved.data();
  // Count per chunk, then fill each chunk's run in storage order (chunks: the result does not
  // depend on the thread count).
  const int64_t chunks = 64, per = (n + chunks - 1) / chunks;
  std::vector<int64_t> at(chunks + 1, 0);
  double asleep2 = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : asleep2)
  for (int64_t c = 0; c < chunks; ++c) {
    int64_t count = 0;
    for (int64_t i = c * per; i < std::min(n, (c + 1) * per); ++i) {
      if (awake[i]) {
        ++count;
      } else if (built && moved[i]) {
        asleep2 = std::max(asleep2, Norm2(p.x[i] - m.x_build[i]));
      }
    }
    at[c + 1] = count;
  }
  for (int64_t c = 0; c < chunks; ++c) at[c + 1] += at[c];
  ResizeWithRoom(m.active, at[chunks]);
  int32_t* active = m.active.data();
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t c = 0; c < chunks; ++c) {
    int64_t k = at[c];
    for (int64_t i = c * per; i < std::min(n, (c + 1) * per); ++i)
      if (awake[i]) {
        active[k++] = static_cast<int32_t>(i);
        moved[i] = 1;
      }
  }
  m.asleep_drift = std::sqrt(asleep2);
  m.stale.active = false;
  m.awake = static_cast<int64_t>(m.active.size());
}

}  // namespace dem::internal

// The force pass: particle-particle contacts over the near list, in vectorised batches, and
// particle-plane contacts, accumulated per particle in a fixed order (even slabs, then odd ones).
// The contact law is Hertz-Mindlin with rolling friction (dem/contact.h gives the equations and
// their sources).
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem::internal {

namespace {

// With sleeping, the force pass visits the busy particles of a large bed (a paper-scale dig:
// ~40,000 of 537,718), scattered through arrays far larger than the caches, and its time went to
// waiting on their loads (perf: the candidate test's x[j], the gather's v, w and 1/|w| of j, the
// scatter's f and t of j). So it asks for them ahead: each candidate's partner data when the
// candidate is tested (the gather and scatter come a batch later), and the position of both
// particles of the slot kPrefetchAhead slots on. Prefetches change no result. Measured in
// journal section 33 (paper_step.csv): the paper snow pass's mid-dig step 1.14x faster; an
// all-awake bed that fits the caches (dig_7mm) 9% slower with them, so they are used only when
// visiting the busy list.
constexpr int32_t kPrefetchAhead = 16;
// A batch is evaluated once fewer than this many contacts would still fit in it.
constexpr size_t kBatchRoom = 8;

// Stores a vector into three structure-of-arrays columns at entry b.
inline void Put(double* cx, double* cy, double* cz, size_t b, const Vec3& a) {
  cx[b] = a.x;
  cy[b] = a.y;
  cz[b] = a.z;
}

// The rolling model of a batch kernel: one of RollingModel's for every contact, or each contact
// its own (kMixedRolling, batches of several material pairs).
constexpr int kEdemRolling = static_cast<int>(RollingModel::kEdem);
constexpr int kCdtRolling = static_cast<int>(RollingModel::kCdt);
constexpr int kLegacyRolling = static_cast<int>(RollingModel::kLegacy);
constexpr int kMixedRolling = 3;

// Hertz-Mindlin forces of a batch of particle pairs: the same law as EvaluateWallContact
// (dem/contact.h: Hertz 1882 normal spring, Tsuji et al. 1992 damping, Mindlin 1949 no-slip
// tangential spring with a Coulomb cap, and the rolling models), written without branches so
// that the compiler runs one contact per SIMD lane (with -fno-trapping-math: dem/CMakeLists.txt).
// kOnePair: every contact has the material pair constants `one`; else each its own columns of the
// batch. kModel: the rolling model (above). kOwnSpins: the batch holds w_i and w_j (wx, wjx
// columns) rather than w_i - w_j.
template <bool kOnePair, int kModel, bool kOwnSpins>
void PairForces(ContactBatch& b, size_t nb, const PairConstants& one, double dt) {
  static_assert(kModel != kEdemRolling || kOwnSpins, "edem rolling needs each particle's spin");
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
    // Contact-point velocity of j relative to i: (v_j - v_i) - (r_i w_i + r_j w_j) x n (the sum
    // gathered, or made here from the spins: the same operations, the same bits).
    const double ax = kOwnSpins ? ri * c.wx[e] + rj * c.wjx[e] : c.ax[e];
    const double ay = kOwnSpins ? ri * c.wy[e] + rj * c.wjy[e] : c.ay[e];
    const double az = kOwnSpins ? ri * c.wz[e] + rj * c.wjz[e] : c.az[e];
    const double vx = c.dvx[e] - (ay * nz - az * ny);
    const double vy = c.dvy[e] - (az * nx - ax * nz);
    const double vz = c.dvz[e] - (ax * ny - ay * nx);
    const double vn = vx * nx + vy * ny + vz * nz;
    const double vtx = vx - vn * nx, vty = vy - vn * ny, vtz = vz - vn * nz;
    // Normal: Hertz spring + damping, no tension.
    const double sq = std::sqrt(r_star * delta);
    const double sn = 2.0 * e_star * sq;
    const double gamma_n = damp * std::sqrt(sn / c.inv_m_star[e]);
    const double fe = 2.0 / 3.0 * sn * delta;  // elastic part
    const double fn = std::max(0.0, fe - gamma_n * vn);
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
    // Rolling friction (RollingTorque in dem/contact.h), each torque capped so that it cannot
    // reverse the spin it acts against within one step: (mix, miy, miz) on i, (mjx, ...) on j.
    double mix = 0, miy = 0, miz = 0, mjx = 0, mjy = 0, mjz = 0;
    const double model = kModel == kMixedRolling ? c.rolling_model[e] : kModel;
    if constexpr (kModel != kEdemRolling) {
      // cdt and legacy: against the relative spin, equal and opposite.
      const double wrx = kOwnSpins ? c.wx[e] - c.wjx[e] : c.wx[e];
      const double wry = kOwnSpins ? c.wy[e] - c.wjy[e] : c.wy[e];
      const double wrz = kOwnSpins ? c.wz[e] - c.wjz[e] : c.wz[e];
      const double w2 = wrx * wrx + wry * wry + wrz * wrz;
      const double wn = std::sqrt(w2);
      const bool cdt = model == kCdtRolling;
      const double force = cdt ? fe : fn;
      const double mr_mag = std::min(rolling * r_star * force, wn / (dt * c.inv_inertia[e]));
      const double mr_f = (rolling > 0.0 && w2 > 0.0) ? -mr_mag / wn : 0.0;
      double mrx = mr_f * wrx, mry = mr_f * wry, mrz = mr_f * wrz;
      if constexpr (kModel != kLegacyRolling) {  // cdt: the torque's normal part removed
        const double mn = mrx * nx + mry * ny + mrz * nz;
        mrx = cdt ? mrx - mn * nx : mrx;
        mry = cdt ? mry - mn * ny : mry;
        mrz = cdt ? mrz - mn * nz : mrz;
      }
      mix = mrx;
      miy = mry;
      miz = mrz;
      mjx = -mrx;
      mjy = -mry;
      mjz = -mrz;
    }
    if constexpr (kOwnSpins && (kModel == kEdemRolling || kModel == kMixedRolling)) {
      // edem: each particle against its own spin, lever r - delta/2:
      //   -min(M_i, |w_i| / (dt ΣI^-1)) w_i / |w_i| = -min(M_i / |w_i|, 1 / (dt ΣI^-1)) w_i,
      // M_i = mu_r (r_i - delta/2) F_n; 1/|w_i| made once per particle (0 for one at rest).
      const double inv_cap = 1.0 / (dt * c.inv_inertia[e]);
      const double fi = -std::min(rolling * (ri - 0.5 * delta) * fn * c.ki[e], inv_cap);
      const double fj = -std::min(rolling * (rj - 0.5 * delta) * fn * c.kj[e], inv_cap);
      const double wix = c.wx[e], wiy = c.wy[e], wiz = c.wz[e];
      const double wjx = c.wjx[e], wjy = c.wjy[e], wjz = c.wjz[e];
      const bool edem = model == kEdemRolling;
      mix = edem ? fi * wix : mix;
      miy = edem ? fi * wiy : miy;
      miz = edem ? fi * wiz : miz;
      mjx = edem ? fj * wjx : mjx;
      mjy = edem ? fj * wjy : mjy;
      mjz = edem ? fj * wjz : mjz;
    }
    // Force on i and the torques on both.
    c.fx[e] = ftx - fn * nx;
    c.fy[e] = fty - fn * ny;
    c.fz[e] = ftz - fn * nz;
    const double cx = ny * ftz - nz * fty, cy = nz * ftx - nx * ftz, cz = nx * fty - ny * ftx;
    c.tix[e] = ri * cx + mix;
    c.tiy[e] = ri * cy + miy;
    c.tiz[e] = ri * cz + miz;
    c.tjx[e] = rj * cx + mjx;
    c.tjy[e] = rj * cy + mjy;
    c.tjz[e] = rj * cz + mjz;
    c.overlap[e] = delta / (2.0 * std::min(ri, rj));
  }
}

// Runs the batch kernel that fits: one pair's constants (`one`, its rolling model) or each
// contact's own (mixed rolling models), with the spins as gathered.
void EvaluateBatch(ContactBatch& b, size_t nb, const PairConstants* one, double dt,
                   bool own_spins) {
  if (one == nullptr) {
    own_spins ? PairForces<false, kMixedRolling, true>(b, nb, PairConstants{}, dt)
              : PairForces<false, kMixedRolling, false>(b, nb, PairConstants{}, dt);
    return;
  }
  switch (one->rolling_model) {
    case RollingModel::kEdem:
      PairForces<true, kEdemRolling, true>(b, nb, *one, dt);
      break;
    case RollingModel::kCdt:
      own_spins ? PairForces<true, kCdtRolling, true>(b, nb, *one, dt)
                : PairForces<true, kCdtRolling, false>(b, nb, *one, dt);
      break;
    case RollingModel::kLegacy:
      own_spins ? PairForces<true, kLegacyRolling, true>(b, nb, *one, dt)
                : PairForces<true, kLegacyRolling, false>(b, nb, *one, dt);
      break;
  }
}

// What the force pass reads and writes, taken once per pass (the arrays do not move during it).
struct PassArrays {
  Vec3* f;  // force [N] (N)
  Vec3* t;  // torque [N m] (N)
  const Vec3 *x, *v, *w;
  const double *radius, *mass, *inv_mass, *inv_inertia;
  const int32_t* mat;
  const uint8_t* awake;
  const double* inv_spin = nullptr;  // with own spins: 1/|w| of each (Workspace::inv_spin)
  // The near list (Workspace::near_k): each slot's partner and history.
  const int32_t *near_j, *near_i;
  int32_t last_slot;  // the near list's last slot
  Vec3* shear;
  uint8_t* touched;
  // Plane candidates and the visits of them.
  const int32_t *wall_start, *wall_k, *wall_visit;
  Vec3* wall_shear;
  const Plane* planes;
  const PairConstants* pair;  // material pair constants (nm x nm)
  const PairConstants* wall;  // particle material x plane (nm x np)
  int nm, np;
  double dt;
  bool compact;      // visit the busy particles only (sleeping)
  bool own_spins;    // gather w_i and w_j, not w_i - w_j (some pair rolls by the edem model)
  int one_material;  // the material of every particle, or -1
  bool alike;        // every particle alike (Alike): these sums stand for the per-particle ones
  double alike_radius, alike_rsum, alike_inv_m_star, alike_inv_inertia;
};

// Totals of one slab.
struct SlabTally {
  double worst = 0;  // deepest overlap / smaller diameter
  int64_t touching = 0, wall_touching = 0;
};

// Particle-particle forces of slab s, batch by batch over its near slots. The hot loop of the step
// (the larger part of a dig's time, docs/dem.md): its three stages (find the touching pairs,
// gather and evaluate them in a batch, accumulate) stay in one body of some 100 lines, as before
// System was split, so that the compiler keeps the arrays in registers across them and no call
// sits inside the batch loop. Splitting it further was not tried.
template <bool kPrefetch>
void SlabPairForces(const PassArrays& a, const Workspace& m, int s, ContactBatch& batch,
                    SlabTally* tally) {
  Vec3* __restrict f = a.f;
  Vec3* __restrict t = a.t;
  const Vec3* x = a.x;
  const Vec3* v = a.v;
  const Vec3* w = a.w;
  const double* radius = a.radius;
  const double* inv_mass = a.inv_mass;
  const double* inv_inertia = a.inv_inertia;
  const int32_t* mat = a.mat;
  const int32_t* near_j = a.near_j;
  const int32_t* near_i = a.near_i;
  Vec3* shear = a.shear;
  uint8_t* touched = a.touched;
  const bool one_material = a.one_material >= 0, alike = a.alike;
  const double alike_rsum = a.alike_rsum;
  const int nm = a.nm;
  const int32_t last_slot = a.last_slot;
  // 1/|w| of each particle (own spins), else any array to prefetch from
  const double* inv_spin = a.inv_spin != nullptr ? a.inv_spin : radius;
  double worst = tally->worst;
  int64_t touching = tally->touching;
  // The slab's slots: its visited particles' near pairs, one after another in visiting order.
  int32_t q = m.slab_slot[s];
  const int32_t q_end = m.slab_slot[s + 1];
  while (q < q_end) {
    // 1. Find the touching pairs among the next slots without branching on the outcome (a
    //    contact is a coin toss for the branch predictor): write every candidate at slot nb and
    //    advance nb only for a contact. `touching` remembers which pairs touched at the last
    //    step; a pair that comes into contact starts with no tangential history. The slots are
    //    taken in runs of at most the batch's room, so none overflows it, until little room is
    //    left; the batch then ends wherever it is, even inside one particle's pairs (the sums of
    //    step 3 add up in slot order whatever the batches).
    size_t nb = 0;
    while (q < q_end && nb + kBatchRoom <= ContactBatch::K) {
      const int32_t run_end =
          static_cast<int32_t>(std::min<int64_t>(q_end, q + (ContactBatch::K - nb)));
      for (; q < run_end; ++q) {
        const int32_t i = near_i[q], j = near_j[q];
        if constexpr (kPrefetch) {
          const int32_t ahead = std::min(q + kPrefetchAhead, last_slot);
          __builtin_prefetch(&x[near_j[ahead]]);
          __builtin_prefetch(&x[near_i[ahead]]);
          __builtin_prefetch(&v[j]);
          __builtin_prefetch(&w[j]);
          __builtin_prefetch(&f[j], 1);
          __builtin_prefetch(&t[j], 1);
          __builtin_prefetch(&inv_spin[j]);
          __builtin_prefetch(&shear[q]);
        }
        // Only the near pairs can touch (see Workspace::near_k); none joins two sleepers (the
        // near list is made again whenever a particle wakes or falls asleep).
        const double rsum = alike ? alike_rsum : radius[i] + radius[j];
        const bool contact = Norm2(x[j] - x[i]) < rsum * rsum;
        batch.i[nb] = i;
        batch.j[nb] = j;
        batch.k[nb] = q;
        batch.was[nb] = touched[q];
        touched[q] = contact;
        nb += contact;
      }
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
      const double ri = alike ? a.alike_radius : radius[i];
      const double rj = alike ? a.alike_radius : radius[j];
      Put(batch.dx, batch.dy, batch.dz, b, x[j] - x[i]);
      Put(batch.dvx, batch.dvy, batch.dvz, b, v[j] - v[i]);
      if (a.own_spins) {  // the kernel makes r_i w_i + r_j w_j and w_i - w_j from these
        Put(batch.wx, batch.wy, batch.wz, b, w[i]);
        Put(batch.wjx, batch.wjy, batch.wjz, b, w[j]);
        batch.ki[b] = a.inv_spin[i];
        batch.kj[b] = a.inv_spin[j];
      } else {
        Put(batch.ax, batch.ay, batch.az, b, ri * w[i] + rj * w[j]);
        Put(batch.wx, batch.wy, batch.wz, b, w[i] - w[j]);
      }
      batch.ri[b] = ri;
      batch.rj[b] = rj;
      batch.inv_m_star[b] = alike ? a.alike_inv_m_star : inv_mass[i] + inv_mass[j];
      batch.inv_inertia[b] = alike ? a.alike_inv_inertia : inv_inertia[i] + inv_inertia[j];
      Put(batch.sx, batch.sy, batch.sz, b, (batch.was[b] ? 1.0 : 0.0) * shear[k]);
    }
    // 2. Contact forces of the batch, one contact per SIMD lane (EvaluateContact, written
    //    without branches), with one material pair's constants for all (the common case) or
    //    each contact's own.
    if (one_material) {
      EvaluateBatch(batch, nb, &a.pair[a.one_material * nm + a.one_material], a.dt, a.own_spins);
    } else if (nb > 0 && uniform) {
      EvaluateBatch(batch, nb, &a.pair[batch.pair[0]], a.dt, a.own_spins);
    } else {
      for (size_t b = 0; b < nb; ++b) {
        const PairConstants& c = a.pair[batch.pair[b]];
        batch.e_star[b] = c.e_star;
        batch.g_star[b] = c.g_star;
        batch.damp[b] = c.damp;
        batch.tangential_ratio[b] = c.tangential_ratio;
        batch.friction[b] = c.friction;
        batch.rolling[b] = c.rolling_friction;
        batch.rolling_model[b] = static_cast<double>(c.rolling_model);
      }
      EvaluateBatch(batch, nb, nullptr, a.dt, a.own_spins);
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
  }
  tally->worst = worst;
  tally->touching = touching;
}

// Particle-plane forces of slab s, after all the slab's pairs: a later block's pairs never reach
// back to an earlier particle (j > i), so each sum adds up in the same order as if the planes
// came right after their particle's block. Each plane's force from the slab goes to
// plane_force (np).
void SlabPlaneForces(const PassArrays& a, const Workspace& m, int s, Vec3* plane_force,
                     SlabTally* tally) {
  const int np = a.np;
  for (int32_t at = m.slab_wall_visit[s]; at < m.slab_wall_visit[s + 1]; ++at) {
    const int32_t i = a.wall_visit[at];
    if (!a.awake[i]) continue;
    const Vec3 xi = a.x[i], vi = a.v[i], wi = a.w[i];
    const double ri = a.radius[i], mi = a.mass[i], inv_ii = a.inv_inertia[i];
    Vec3 fi, ti;
    // Particle-plane contacts of i (R* = r_i, m* = m_i: the wall is rigid and fixed).
    for (int32_t e = a.wall_start[i]; e < a.wall_start[i + 1]; ++e) {
      const Plane& pl = a.planes[a.wall_k[e]];
      const double delta = ri - Dot(xi - pl.point, pl.normal);
      if (delta <= 0.0) {
        a.wall_shear[e] = Vec3{};
        continue;
      }
      const Vec3 nrm = -pl.normal;  // from the particle to the wall
      const Vec3 v_rel = -(vi + ri * Cross(wi, nrm));
      const ContactForce cf =
          EvaluateWallContact(a.wall[a.mat[i] * np + a.wall_k[e]], nrm, delta, ri, mi, v_rel, wi,
                              Vec3{}, inv_ii, a.dt, a.wall_shear[e]);
      const Vec3 fa = cf.ft - cf.fn * nrm;
      fi += fa;
      ti += ri * Cross(nrm, cf.ft) + cf.mr;
      plane_force[a.wall_k[e]] -= fa;
      tally->worst = std::max(tally->worst, delta / (2.0 * ri));
      ++tally->wall_touching;
    }
    a.f[i] += fi;
    a.t[i] += ti;
  }
}

// Each particle's 1/|w| (0 when w = 0), for the edem rolling torque, unless KickDrift made them
// this step. Made for every particle when the storage changed (stale.spins), sleeping is off, or
// the list of the awake ones is stale; else for the awake ones only: a sleeper's spin is zero,
// and so is its entry (zeroed with the spin when it fell asleep, UpdateSleep).
void UpdateInvSpins(Workspace& m, const Particles& p, bool sleeping, int nt) {
  const int64_t n = static_cast<int64_t>(p.size());
  // KickDrift made them for the particles it moved, which are the awake ones (and all without
  // sleeping) unless the list of those or the storage changed since.
  if (m.inv_spin_kicked && !m.stale.spins && !m.stale.active && m.inv_spin.size() == p.size())
    return;
  const bool all = !sleeping || m.stale.spins || m.stale.active || m.inv_spin.size() != p.size();
  if (m.inv_spin.size() != p.size()) m.inv_spin.resize(n);
  double* inv_spin = m.inv_spin.data();
  const Vec3* w = p.w.data();
  const int32_t* active = m.active.data();
  const int64_t count = all ? n : static_cast<int64_t>(m.active.size());
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t a = 0; a < count; ++a) {
    const int64_t i = all ? a : active[a];
    inv_spin[i] = InvNorm(w[i]);
  }
  m.stale.spins = false;
}

PassArrays TakeArrays(Workspace& m, Particles& p, const SystemConfig& config, int nm) {
  PassArrays a;
  a.f = p.f.data();
  a.t = p.t.data();
  a.x = p.x.data();
  a.v = p.v.data();
  a.w = p.w.data();
  a.radius = p.radius.data();
  a.mass = p.mass.data();
  a.inv_mass = p.inv_mass.data();
  a.inv_inertia = p.inv_inertia.data();
  a.mat = p.material.data();
  a.awake = p.awake.data();
  a.near_j = m.near_j.data();
  a.near_i = m.near_i.data();
  a.last_slot = static_cast<int32_t>(std::max<int64_t>(0, m.near_pairs - 1));
  a.shear = m.near_shear.data();  // the near slots hold the history (Workspace::near_k)
  a.touched = m.near_touch.data();
  a.wall_start = m.wall_start.data();
  a.wall_k = m.wall_k.data();
  a.wall_visit = m.wall_visit.data();
  a.wall_shear = m.wall_shear.data();
  a.planes = config.planes.data();
  a.pair = m.pair.data();
  a.wall = m.wall.data();
  a.nm = nm;
  a.np = static_cast<int>(config.planes.size());
  a.dt = config.time_step;
  a.compact = config.sleep.enabled;
  // The particles' own spins are gathered when a pair that can occur rolls by the edem model.
  a.own_spins = false;
  for (int k = 0; k < nm * nm; ++k) {
    const bool occurs = m.particle_material < 0 || k == m.particle_material * (nm + 1);
    a.own_spins = a.own_spins || (occurs && m.pair[k].rolling_model == RollingModel::kEdem);
  }
  a.one_material = m.particle_material;
  a.alike = m.alike.all;  // each sum below is the one the per-particle arrays would give
  a.alike_radius = m.alike.radius;
  a.alike_rsum = m.alike.radius + m.alike.radius;
  a.alike_inv_m_star = m.alike.inv_mass + m.alike.inv_mass;
  a.alike_inv_inertia = m.alike.inv_inertia + m.alike.inv_inertia;
  return a;
}

}  // namespace

void ComputeForces(Workspace& m, Particles& p, const SystemConfig& config, int nm, int nt,
                   PhaseTimes* times, std::vector<Vec3>* plane_force,
                   const std::function<void()>& motion) {
  const int nslabs = m.list.num_slabs();
  const int np = static_cast<int>(config.planes.size());
  m.slab_overlap.assign(nslabs, 0.0);
  m.slab_contacts.assign(nslabs, 0);
  m.slab_wall_contacts.assign(nslabs, 0);
  m.slab_plane_force.assign(static_cast<size_t>(nslabs) * np, Vec3{});
  // The lists the pass walks, made again where stale.
  const bool compact = config.sleep.enabled;
  const double t_near = Now();
  if (compact && m.stale.busy) RefreshBusy(m, p, nt);
  if (m.stale.near) BuildNear(m, p, compact, nt);
  if (m.stale.walls) ListWallVisits(m, compact, nt);
  if (!m.near_owners) ListSlotOwners(m, p, compact, nt);
  const double t_pairs = Now();
  times->near += t_pairs - t_near;
  PassArrays arrays = TakeArrays(m, p, config, nm);
  if (arrays.own_spins) {
    UpdateInvSpins(m, p, compact, nt);
    arrays.inv_spin = m.inv_spin.data();
  }
  m.want_inv_spin = arrays.own_spins;
  m.inv_spin_kicked = false;
  if (m.batches.size() < static_cast<size_t>(nt)) m.batches.resize(nt);

  // Each thread takes one contiguous run of the even slabs, then of the odd ones (see neighbor.h
  // for why the two phases are race-free and deterministic), split by the slabs' weights, so the
  // same thread meets the same particles step after step and their data stays in its core's
  // cache; the kicks' static schedule over the particles (sorted by slab) mostly agrees with it.
  // A thread done with its run takes the next slabs of the others' (the weights are not the
  // time: touching pairs cost more than near ones, and a core may be busy with another job).
  // No result depends on who makes a slab's sums. Measured against a heaviest-first dynamic
  // schedule: journal section 12.
  const bool weighed = m.slab_weight.size() == static_cast<size_t>(nslabs);
  SlabRuns::Run* runs = m.slab_runs.Get(2 * nt);
  for (int phase = 0; phase < 2; ++phase) {      // phase p's slabs are p, p + 2, ...: position k
    const int count = (nslabs - phase + 1) / 2;  // is slab phase + 2 k
    int64_t total = 0;
    for (int k = 0; k < count; ++k) total += weighed ? m.slab_weight[phase + 2 * k] : 1;
    int64_t before = 0;  // the weight of the slabs before position k
    int owner = 0;       // each run starts where its share of the total weight starts
    for (int r = 0; r < nt; ++r) runs[phase * nt + r].next.store(count, std::memory_order_relaxed);
    for (int k = 0; k < count; ++k) {
      const int64_t w = weighed ? m.slab_weight[phase + 2 * k] : 1;
      // The slab goes to the run whose share holds its weight's midpoint.
      const int r =
          total > 0
              ? static_cast<int>(std::min<int64_t>(nt - 1, ((2 * before + w) * nt) / (2 * total)))
              : 0;
      for (; owner <= r; ++owner) runs[phase * nt + owner].next.store(k, std::memory_order_relaxed);
      before += w;
    }
    for (int r = 0; r < nt; ++r)
      runs[phase * nt + r].end =
          r + 1 < nt ? runs[phase * nt + r + 1].next.load(std::memory_order_relaxed) : count;
  }
  double t_motion = 0;  // the time `motion` took on its thread
  int team = 1;         // the threads the runtime gave
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num();
    // The caller's work, on the team's last thread; the others take this one's slabs meanwhile.
    if (motion && t == omp_get_num_threads() - 1) {
      team = omp_get_num_threads();
      const double t0 = Now();
      motion();
      t_motion = Now() - t0;
    }
    for (int phase = 0; phase < 2; ++phase) {
      for (int d = 0; d < nt; ++d) {  // its own run, then what is left of the others'
        SlabRuns::Run& run = runs[phase * nt + (t + d) % nt];
        for (int k; (k = run.next.fetch_add(1, std::memory_order_relaxed)) < run.end;) {
          const int s = phase + 2 * k;
          SlabTally tally;
          if (compact) {
            SlabPairForces<true>(arrays, m, s, m.batches[t], &tally);
          } else {
            SlabPairForces<false>(arrays, m, s, m.batches[t], &tally);
          }
          SlabPlaneForces(arrays, m, s, m.slab_plane_force.data() + static_cast<size_t>(s) * np,
                          &tally);
          m.slab_overlap[s] = tally.worst;
          m.slab_contacts[s] = tally.touching;
          m.slab_wall_contacts[s] = tally.wall_touching;
        }
      }
      if (phase == 0) {
#pragma omp barrier
      }
    }
  }
  // Reductions over slabs in slab order (independent of the thread count).
  std::fill(plane_force->begin(), plane_force->end(), Vec3{});
  m.contacts = m.wall_contacts = 0;
  double worst = 0;
  for (int s = 0; s < nslabs; ++s) {
    for (int k = 0; k < np; ++k)
      (*plane_force)[k] += m.slab_plane_force[static_cast<size_t>(s) * np + k];
    m.contacts += m.slab_contacts[s];
    m.wall_contacts += m.slab_wall_contacts[s];
    worst = std::max(worst, m.slab_overlap[s]);
  }
  m.max_overlap = worst;
  // On one thread `motion` ran in series: not a part of the pair forces' time.
  times->pairs += Now() - t_pairs - (team == 1 ? t_motion : 0.0);
}

}  // namespace dem::internal

// The parallel bond (dem/bond.h gives the law, its equations and sources): MakeBond,
// BondCriticalStep, the bond's energy and stresses, and the step's bond phase (BondForces), which
// System::Step runs after the mesh contacts and before the second half kick. Built with
// SCOOPSIM_NO_FUSED_FLAGS (dem/CMakeLists.txt): its cross products and rotations are the pattern
// GCC fuses into multiply-add/subtract pairs.
#include "dem/bond.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "dem/internal_grow.h"
#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem {

namespace {

// Area, moment of inertia and polar moment of the bond's disk: pi R^2, pi R^4 / 4, pi R^4 / 2.
struct Disk {
  double area, inertia, polar;
};
inline Disk DiskOf(double radius) {
  const double r2 = radius * radius;
  return {M_PI * r2, 0.25 * M_PI * r2 * r2, 0.5 * M_PI * r2 * r2};
}

// The turn of the contact plane over a step, applied to the vectors of the plane (the shear
// force, the bending moment): the smallest rotation taking unit n0 to unit n1 (Rodrigues: with
// k = n0 x n1, c = n0 . n1, R v = c v + k x v + k (k . v) / (1 + c), exact for any angle below
// pi), then one about n1 by the angle 2 atan(s / 2) (Cayley: with t = s / 2,
// v + 2 / (1 + t^2) (t n1 x v + t^2 n1 x (n1 x v)), a rotation exact in length, of angle
// s - s^3 / 12 + ...); what rounding left along n1 is dropped.
struct PlaneTurn {
  Vec3 k, n1;
  double c, inv_1c, t, cayley;
  PlaneTurn(const Vec3& n0, const Vec3& n1_in, double s)
      : k(Cross(n0, n1_in)), n1(n1_in), c(Dot(n0, n1_in)), t(0.5 * s) {
    inv_1c = c > -0.5 ? 1.0 / (1.0 + c) : 0.0;  // n flipped within a step: keep v's direction
    cayley = 2.0 / (1.0 + t * t);
  }
  Vec3 operator()(const Vec3& v) const {
    Vec3 r = c > -0.5 ? c * v + Cross(k, v) + (Dot(k, v) * inv_1c) * k : v;
    const Vec3 nv = Cross(n1, r);
    r += cayley * (t * nv + (t * t) * Cross(n1, nv));
    return r - Dot(r, n1) * n1;
  }
};

}  // namespace

Bond MakeBond(int64_t ida, double ra, int64_t idb, double rb, double distance,
              const BondParams& params, double strength_scale) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("MakeBond: " + what);
  };
  require(ra > 0 && rb > 0, "the radii must be > 0");
  require(distance > 0, "the distance must be > 0");
  require(params.radius_multiplier > 0 && std::isfinite(params.radius_multiplier),
          "radius_multiplier must be > 0");
  require(params.modulus > 0 && std::isfinite(params.modulus), "modulus must be > 0");
  require(params.stiffness_ratio > 0 && std::isfinite(params.stiffness_ratio),
          "stiffness_ratio must be > 0");
  require(strength_scale > 0, "strength_scale must be > 0");
  require(params.tensile_strength * strength_scale > 0, "tensile_strength must be > 0");
  require(params.cohesion * strength_scale > 0, "cohesion must be > 0");
  require(params.friction_angle >= 0 && params.friction_angle < 0.5 * M_PI,
          "friction_angle must be in [0, pi/2) rad");
  require(params.damping_ratio >= 0 && std::isfinite(params.damping_ratio),
          "damping_ratio must be >= 0");
  Bond b;
  b.a = std::min(ida, idb);
  b.b = std::max(ida, idb);
  b.radius = params.radius_multiplier * std::min(ra, rb);
  b.kn = params.modulus / (ra + rb);
  b.ks = b.kn / params.stiffness_ratio;
  b.tensile_strength = params.tensile_strength * strength_scale;
  b.cohesion = params.cohesion * strength_scale;
  b.tan_friction = std::tan(params.friction_angle);
  b.damping_ratio = params.damping_ratio;
  return b;
}

// The critical step. Two equal spheres (radius r, mass m = 4/3 pi r^3 rho, moment of inertia
// I = 2/5 m r^2) joined by one bond (K_n = k_n A, K_s = k_s A, K_t = k_s J, K_b = k_n I_b, with
// k_n = E_b / 2r), linearised about rest. Besides the free motion of the pair as a rigid body,
// with u the relative displacement of b, theta_a, theta_b the rotations (lever r from each centre
// to the contact point), the bond's energy is
//   1/2 K_n u_n^2 + 1/2 K_s |u_s - r n x (theta_a + theta_b)|^2 + 1/2 K_t (theta_b - theta_a)_n^2
//   + 1/2 K_b |(theta_b - theta_a)_s|^2
// and the kinetic energy 1/2 (m/2) |u'|^2 + 1/2 I (|theta_a'|^2 + |theta_b'|^2). In the
// coordinates u, theta+ = (theta_a + theta_b)/2 (inertia 2I) and theta- = theta_b - theta_a
// (inertia I/2) the modes separate:
//   axial              omega^2 = K_n / (m/2)                       = 2 K_n / m
//   shear and rotation u_s with theta+ (slip u_s - 2 r theta+): omega^2 = K_s (2/m + (2r)^2/(2I))
//                                                                  = 7 K_s / m
//   twist              omega^2 = K_t / (I/2)                       = 2 K_t / I
//   bending            omega^2 = K_b / (I/2)                       = 2 K_b / I
// (the other shear/rotation combination, u_s = 2 r theta+, is a rigid rotation: omega = 0). The
// shear spring's lever makes its mode sqrt(3.5) faster than the bare translation's. Velocity
// Verlet is stable for omega dt < 2, and with viscous damping of ratio z for
// omega dt < 2 (sqrt(1 + z^2) - z). A sphere with many bonds: the stiffness is the sum of the
// bonds' own, each bounded by omega_max^2 times its spheres' mass (in the mass-weighted norm), and
// a sphere appears in at most n_b of them, so the whole system's omega^2 is at most
// n_b omega_max^2 (a Gershgorin-type bound); with n_b = 12 (the kissing number of equal spheres:
// a bonding gap well below the radius admits no more) the step is divided by sqrt(12). Measured
// (5 x 5 x 5 lattices kicked at random, E_b 1e8 Pa, k_n/k_s 1-3, lambda 0.5-1): a simple cubic
// lattice (6 bonds a sphere) goes unstable from 2-2.5x this step, an fcc one (12) from 1.5x; at
// 1x the energy of the cubic lattice, taken at full steps, swings by 10% (Verlet's (omega dt)^2/4
// for its fastest modes; 2.4% at 0.5x), which tests/dem/bond_test.cpp checks with the
// instability at 3x. So the bound is tight for the densest packing; a run that wants its bond
// energy to 1% takes a third of it. Contacts are not counted: the caller takes the smaller of
// this and the contact's step. Zero modulus: no limit (+inf).
double BondCriticalStep(double radius, double density, const BondParams& params) {
  const double r = radius;
  const double m = 4.0 / 3.0 * M_PI * r * r * r * density;
  const double inertia = 0.4 * m * r * r;
  const Disk disk = DiskOf(params.radius_multiplier * r);
  const double kn = params.modulus / (2.0 * r), ks = kn / params.stiffness_ratio;
  const double w2 = std::max({2.0 * kn * disk.area / m, 7.0 * ks * disk.area / m,
                              2.0 * ks * disk.polar / inertia, 2.0 * kn * disk.inertia / inertia});
  const double z = params.damping_ratio;
  const double stable = 2.0 * (std::sqrt(1.0 + z * z) - z) / std::sqrt(w2);
  return stable / std::sqrt(12.0);
}

double BondEnergy(const Bond& b) {
  const Disk d = DiskOf(b.radius);
  return b.fn * b.fn / (2.0 * b.kn * d.area) + Norm2(b.fs) / (2.0 * b.ks * d.area) +
         b.mt * b.mt / (2.0 * b.ks * d.polar) + Norm2(b.mb) / (2.0 * b.kn * d.inertia);
}

double BondSigma(const Bond& b) {
  const Disk d = DiskOf(b.radius);
  return b.fn / d.area + Norm(b.mb) * b.radius / d.inertia;
}

double BondTau(const Bond& b) {
  const Disk d = DiskOf(b.radius);
  return Norm(b.fs) / d.area + std::abs(b.mt) * b.radius / d.polar;
}

namespace internal {

namespace {

constexpr uint8_t kBroke = 1, kWakeA = 2, kWakeB = 4;

// One live bond's step (dem/bond.h): its state carried with the contact plane and incremented,
// the break test, the force and torques on its two spheres into its slots. A bond between two
// sleepers is left as it is (frozen). Returns the event bits (kBroke, kWakeA, kWakeB).
inline uint8_t StepBond(Bond& b, const BondConstants& c, int32_t i, int32_t j, const Particles& p,
                        bool sleeping, double wake2, double dt, Vec3* force_b, Vec3* torque_a,
                        Vec3* torque_b) {
  *force_b = *torque_a = *torque_b = Vec3{};
  const bool awake_a = !sleeping || p.awake[i], awake_b = !sleeping || p.awake[j];
  if (!awake_a && !awake_b) return 0;
  uint8_t event = 0;
  if (!awake_b && Norm2(p.v[i]) > wake2) event |= kWakeB;
  if (!awake_a && Norm2(p.v[j]) > wake2) event |= kWakeA;
  // Geometry: normal, gap, levers from the centres to the contact point.
  const Vec3 d = p.x[j] - p.x[i];
  const double dist = Norm(d);
  const Vec3 n = (1.0 / dist) * d;
  const double half_gap = 0.5 * (dist - p.radius[i] - p.radius[j]);
  const double lever_a = p.radius[i] + half_gap, lever_b = p.radius[j] + half_gap;
  // Relative motion of b against a at the contact point, and relative spin.
  const Vec3 wa = p.w[i], wb = p.w[j];
  const Vec3 v_rel = (p.v[j] - p.v[i]) - Cross(lever_a * wa + lever_b * wb, n);
  const double vn = Dot(v_rel, n);
  const Vec3 vs = v_rel - vn * n;
  const Vec3 w_rel = wb - wa;
  const double wn = Dot(w_rel, n);
  const Vec3 ws = w_rel - wn * n;
  // The state carried with the contact plane, then this step's increments.
  const PlaneTurn turn(b.normal, n, 0.5 * Dot(wa + wb, n) * dt);
  b.fs = turn(b.fs);
  b.mb = turn(b.mb);
  b.normal = n;
  b.fn += c.kn_area * (vn * dt);
  b.fs -= (c.ks_area * dt) * vs;
  b.mt -= c.ks_polar * (wn * dt);
  b.mb -= (c.kn_inertia * dt) * ws;
  // Break test (dem/bond.h): tension first, then Mohr-Coulomb shear.
  const double sigma_n = b.fn * c.inv_area;
  const double sigma = sigma_n + Norm(b.mb) * c.rim_over_inertia;
  const double tau = Norm(b.fs) * c.inv_area + std::abs(b.mt) * c.rim_over_polar;
  if (sigma >= b.tensile_strength || tau >= b.cohesion - sigma_n * b.tan_friction) {
    b.intact = false;
    return kBroke | kWakeA | kWakeB;
  }
  // Force and moment on b, with the damping (not stored; zero coefficients without it).
  const Vec3 f = (b.fs - b.fn * n) - ((c.damp_n * vn) * n + c.damp_s * vs);
  const Vec3 moment = (b.mb + b.mt * n) - ((c.damp_t * wn) * n + c.damp_b * ws);
  // Torques about the centres: x_c - x_b = -lever_b n, x_c - x_a = lever_a n.
  const Vec3 nf = Cross(n, f);
  *force_b = f;
  *torque_b = moment - lever_b * nf;
  *torque_a = -moment - lever_a * nf;
  return event;
}

// The constants of a live bond: its springs, stresses and damping (StepBond).
BondConstants ConstantsOf(const Bond& b, const Particles& p, int32_t i, int32_t j) {
  const Disk disk = DiskOf(b.radius);
  BondConstants c;
  c.kn_area = b.kn * disk.area;
  c.ks_area = b.ks * disk.area;
  c.ks_polar = b.ks * disk.polar;
  c.kn_inertia = b.kn * disk.inertia;
  c.inv_area = 1.0 / disk.area;
  c.rim_over_inertia = b.radius / disk.inertia;
  c.rim_over_polar = b.radius / disk.polar;
  if (b.damping_ratio > 0.0) {
    // 2 z sqrt(k m*) with the pair's reduced mass and moment of inertia (I = 2/5 m r^2).
    const double ma = p.mass[i], mb = p.mass[j];
    const double m_star = ma * mb / (ma + mb);
    const double ia = 0.4 * ma * p.radius[i] * p.radius[i];
    const double ib = 0.4 * mb * p.radius[j] * p.radius[j];
    const double i_star = ia * ib / (ia + ib);
    const double z2 = 2.0 * b.damping_ratio;
    c.damp_n = z2 * std::sqrt(c.kn_area * m_star);
    c.damp_s = z2 * std::sqrt(c.ks_area * m_star);
    c.damp_t = z2 * std::sqrt(c.ks_polar * i_star);
    c.damp_b = z2 * std::sqrt(c.kn_inertia * i_star);
  }
  return c;
}

}  // namespace

void IndexBonds(Workspace& m, const Particles& p) {
  BondWork& w = m.bond;
  w.Sync();
  const size_t n = p.size();
  // Storage index of each persistent id.
  int64_t max_id = -1;
  for (size_t i = 0; i < n; ++i) max_id = std::max(max_id, p.id[i]);
  std::vector<int32_t>& index = w.index_of_id;
  index.assign(static_cast<size_t>(max_id + 1), -1);
  for (size_t i = 0; i < n; ++i) index[p.id[i]] = static_cast<int32_t>(i);
  // The intact bonds in bond order (k), their spheres' storage indices (AddBonds and
  // RemoveParticles keep every bond's spheres present).
  std::vector<int32_t>& in_order = w.fill;
  in_order.clear();
  for (size_t k = 0; k < w.bonds.size(); ++k)
    if (w.bonds[k].intact) in_order.push_back(static_cast<int32_t>(k));
  const size_t nl = in_order.size();
  std::vector<int32_t>& sa = w.scratch_a;
  std::vector<int32_t>& sb = w.scratch_b;
  sa.resize(nl);
  sb.resize(nl);
  for (size_t k = 0; k < nl; ++k) {
    sa[k] = index[w.bonds[in_order[k]].a];
    sb[k] = index[w.bonds[in_order[k]].b];
  }
  // The processing order (q): by the lower storage index of the two spheres (a counting sort,
  // stable), so that the bond pass reads the particles nearly in storage order.
  std::vector<int32_t>& pos = w.scratch_pos;
  pos.resize(nl);
  w.start.assign(n + 1, 0);
  for (size_t k = 0; k < nl; ++k) ++w.start[std::min(sa[k], sb[k]) + 1];
  for (size_t i = 0; i < n; ++i) w.start[i + 1] += w.start[i];
  for (size_t k = 0; k < nl; ++k) pos[k] = w.start[std::min(sa[k], sb[k])]++;
  w.live.resize(nl);
  w.hot.resize(nl);
  w.ia.resize(nl);
  w.ib.resize(nl);
  for (size_t k = 0; k < nl; ++k) {
    w.live[pos[k]] = in_order[k];
    w.hot[pos[k]] = w.bonds[in_order[k]];
    w.ia[pos[k]] = sa[k];
    w.ib[pos[k]] = sb[k];
  }
  // Each particle's bond ends, in bond order (a counting sort over k), naming their slots q.
  w.start.assign(n + 1, 0);
  for (size_t k = 0; k < nl; ++k) {
    ++w.start[sa[k] + 1];
    ++w.start[sb[k] + 1];
  }
  for (size_t i = 0; i < n; ++i) w.start[i + 1] += w.start[i];
  ResizeWithRoom(w.entry, 2 * nl);
  std::vector<int32_t>& at = w.scratch_at;
  at.assign(w.start.begin(), w.start.end() - 1);
  for (size_t k = 0; k < nl; ++k) {
    w.entry[at[sa[k]]++] = 2 * pos[k];
    w.entry[at[sb[k]]++] = 2 * pos[k] + 1;
  }
  w.constants.resize(nl);
  for (size_t q = 0; q < nl; ++q) w.constants[q] = ConstantsOf(w.hot[q], p, w.ia[q], w.ib[q]);
  ResizeWithRoom(w.force_b, nl);
  ResizeWithRoom(w.torque_a, nl);
  ResizeWithRoom(w.torque_b, nl);
  ResizeWithRoom(w.event, nl);
  w.stale = false;
}

void BondForces(Workspace& m, Particles& p, const SleepConfig& sleep, double dt, double t_end,
                int nt) {
  BondWork& w = m.bond;
  if (w.bonds.empty()) return;
  if (w.stale) IndexBonds(m, p);
  const int64_t nl = static_cast<int64_t>(w.live.size());
  if (nl == 0) return;
  const bool sleeping = sleep.enabled;
  const double wake2 = sleep.wake_speed * sleep.wake_speed;
  // 1. Each live bond on its own: its state, its result slots.
  int any = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(| : any)
  for (int64_t q = 0; q < nl; ++q) {
    w.event[q] = StepBond(w.hot[q], w.constants[q], w.ia[q], w.ib[q], p, sleeping, wake2, dt,
                          &w.force_b[q], &w.torque_a[q], &w.torque_b[q]);
    any |= w.event[q];
  }
  w.hot_ahead = true;
  // 2. Each particle sums its bonds in bond order; a sleeper that a bond wakes starts at rest in
  // equilibrium (zero force and torque, as a sleeper woken by a touch).
  const int64_t n = static_cast<int64_t>(p.size());
  int woke = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(| : woke)
  for (int64_t i = 0; i < n; ++i) {
    const int32_t e0 = w.start[i], e1 = w.start[i + 1];
    if (e0 == e1) continue;
    if (sleeping && !p.awake[i]) {
      bool wake = false;
      for (int32_t e = e0; e < e1; ++e)
        wake = wake || (w.event[w.entry[e] >> 1] & ((w.entry[e] & 1) ? kWakeB : kWakeA)) != 0;
      if (wake) {
        p.awake[i] = 1;
        p.f[i] = Vec3{};
        p.t[i] = Vec3{};
        woke = 1;
      }
      continue;
    }
    Vec3 fi, ti;
    for (int32_t e = e0; e < e1; ++e) {
      const int32_t q = w.entry[e] >> 1;
      if (w.entry[e] & 1) {
        fi += w.force_b[q];
        ti += w.torque_b[q];
      } else {
        fi -= w.force_b[q];
        ti += w.torque_a[q];
      }
    }
    p.f[i] += fi;
    p.t[i] += ti;
  }
  if (woke) {
    m.stale.busy = true;
    m.stale.active = true;
  }
  // 3. The breaks, in bond order.
  if (!(any & kBroke)) return;
  std::vector<int32_t>& broke = w.scratch_pos;
  broke.clear();
  for (int64_t q = 0; q < nl; ++q)
    if (w.event[q] & kBroke) broke.push_back(static_cast<int32_t>(q));
  std::sort(broke.begin(), broke.end(),
            [&w](int32_t l, int32_t r) { return w.live[l] < w.live[r]; });
  for (const int32_t q : broke) {
    const Bond& b = w.hot[q];
    const Vec3 xa = p.x[w.ia[q]], xb = p.x[w.ib[q]];
    const double dist = Norm(xb - xa);
    const double lever_a = 0.5 * (dist + p.radius[w.ia[q]] - p.radius[w.ib[q]]);
    BondBreak br;
    br.time = t_end;
    br.a = b.a;
    br.b = b.b;
    br.position = xa + (lever_a / dist) * (xb - xa);
    br.mode = BondSigma(b) >= b.tensile_strength ? BondBreakMode::kTension : BondBreakMode::kShear;
    br.stress = br.mode == BondBreakMode::kTension ? BondSigma(b) : BondTau(b);
    w.breaks.push_back(br);
  }
  w.stale = true;  // the live list lost them (Sync puts them back into `bonds`, broken)
}

}  // namespace internal

}  // namespace dem

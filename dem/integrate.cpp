// Integration: the two half kicks and the drift of velocity Verlet (LIGGGHTS fix nve/sphere;
// Allen & Tildesley eq. 3.19), and the drift test that decides when the neighbour list is built
// again. System::Step (dem/system.cpp) runs them around the force passes.
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem::internal {

double KickDrift(Workspace& m, Particles& p, const SystemConfig& config, int nt,
                 const int32_t* clump_of) {
  const double dt = config.time_step;
  const double h = 0.5 * dt;
  Vec3* x = p.x.data();
  Vec3* v = p.v.data();
  Vec3* w = p.w.data();
  Vec3* f = p.f.data();
  Vec3* t = p.t.data();
  const double* mass = p.mass.data();
  const double* inv_mass = p.inv_mass.data();
  const double* inv_inertia = p.inv_inertia.data();
  const Vec3 g = config.gravity;
  // With sleeping, only the awake particles (Workspace::active) move; a sleeper's force and
  // torque are not kept up to date (they are zeroed when it wakes: a sleeper is at rest in
  // equilibrium).
  const bool sleeping = config.sleep.enabled;
  const int32_t* active = m.active.data();
  const int64_t n_moving = static_cast<int64_t>(sleeping ? m.active.size() : p.size());
  // Alike particles (Workspace::AlikeNow): the same numbers as the per-particle arrays hold,
  // without streaming them.
  const bool alike = m.AlikeNow();
  const double alike_mass = m.alike.mass, alike_inv_mass = m.alike.inv_mass,
               alike_inv_inertia = m.alike.inv_inertia;
  // 1/|w| of each moved particle for the edem rolling torque (Workspace::inv_spin), while w is
  // at hand.
  double* inv_spin = m.want_inv_spin && m.inv_spin.size() == p.size() ? m.inv_spin.data() : nullptr;
  m.inv_spin_kicked = inv_spin != nullptr;
  // A clump's sphere only counts in the largest |v|^2 (the same operations); BeginStep places it.
  // Two loops, so that a bed of spheres alone runs the loop it ran before clumps were tested.
  const auto kick_drift = [&](auto with_clumps) {
    double max_v2 = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : max_v2)
    for (int64_t a = 0; a < n_moving; ++a) {
      const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
      if constexpr (decltype(with_clumps)::value) {
        if (clump_of[i] >= 0) {
          max_v2 =
              std::max(max_v2, Norm2(v[i] + (h * (alike ? alike_inv_mass : inv_mass[i])) * f[i]));
          continue;
        }
      }
      v[i] += (h * (alike ? alike_inv_mass : inv_mass[i])) * f[i];
      w[i] += (h * (alike ? alike_inv_inertia : inv_inertia[i])) * t[i];
      if (inv_spin != nullptr) inv_spin[i] = InvNorm(w[i]);
      x[i] += dt * v[i];
      max_v2 = std::max(max_v2, Norm2(v[i]));
      // Start this step's force with gravity (contacts add to it in ComputeForces).
      f[i] = (alike ? alike_mass : mass[i]) * g;
      t[i] = Vec3{};
    }
    return max_v2;
  };
  return clump_of != nullptr ? kick_drift(std::true_type{}) : kick_drift(std::false_type{});
}

bool NeedsRebuild(Workspace& m, const Particles& p, double step_bound, bool sleeping, int nt) {
  // Rebuild when some particle has moved more than skin/2 since the last build. The sum of
  // dt * max |v| bounds every displacement (triangle inequality); only when that bound passes
  // skin/2 are the true displacements measured, and the bound restarts from the largest one.
  const size_t n = p.size();
  const double half_skin = 0.5 * m.skin;
  const bool have_build = !m.stale.list && m.x_build.size() == n;
  m.drift_bound += step_bound;
  bool rebuild = m.stale.rebuild || !have_build;
  if (!rebuild && m.drift_bound > half_skin) {
    // With sleeping only the awake particles can have moved on; the sleepers' share is kept in
    // asleep_drift.
    double max_disp2 = m.asleep_drift * m.asleep_drift;
    const Vec3* x = p.x.data();
    const Vec3* xb = m.x_build.data();
    const int32_t* active = m.active.data();
    const int64_t n_moving = static_cast<int64_t>(sleeping ? m.active.size() : n);
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : max_disp2)
    for (int64_t a = 0; a < n_moving; ++a) {
      const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
      max_disp2 = std::max(max_disp2, Norm2(x[i] - xb[i]));
    }
    m.drift_bound = std::sqrt(max_disp2);
    rebuild = !(m.drift_bound <= half_skin);  // also on NaN
  }
  // The mesh candidates and the near list keep their own bounds.
  for (MeshState& ms : m.meshes) ms.particle_drift += step_bound;
  m.near_bound += step_bound;
  if (!(m.near_bound <= 0.5 * m.near_skin)) m.stale.near = true;  // also on NaN
  return rebuild;
}

bool Kick(const Workspace& m, Particles& p, double dt, bool sleeping, int nt, double* max_v2_out) {
  const double h = 0.5 * dt;
  Vec3* v = p.v.data();
  Vec3* w = p.w.data();
  const Vec3* f = p.f.data();
  const Vec3* t = p.t.data();
  const double* inv_mass = p.inv_mass.data();
  const double* inv_inertia = p.inv_inertia.data();
  const int32_t* active = m.active.data();
  const int64_t n_kicked = static_cast<int64_t>(sleeping ? m.active.size() : p.size());
  const bool alike = m.AlikeNow();  // noted again if this step rebuilt
  const double alike_inv_mass = m.alike.inv_mass, alike_inv_inertia = m.alike.inv_inertia;
  double max_v2 = 0;
  int bad = 0;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : max_v2) reduction(| : bad)
  for (int64_t a = 0; a < n_kicked; ++a) {
    const size_t i = sleeping ? static_cast<size_t>(active[a]) : static_cast<size_t>(a);
    v[i] += (h * (alike ? alike_inv_mass : inv_mass[i])) * f[i];
    w[i] += (h * (alike ? alike_inv_inertia : inv_inertia[i])) * t[i];
    const double v2 = Norm2(v[i]);
    // A finite v keeps x finite (x += dt v), so x need not be read here.
    if (!(std::isfinite(v2) && IsFinite(w[i]))) bad = 1;
    max_v2 = std::max(max_v2, v2);
  }
  *max_v2_out = max_v2;
  return !bad;
}

}  // namespace dem::internal

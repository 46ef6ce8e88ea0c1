// The System's totals over all particles (energies, momentum) and its state hash, each summed in
// persistent-id order so that it does not depend on storage order or thread count.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "dem/contact.h"
#include "dem/internal_workspace.h"
#include "dem/system.h"

namespace dem {

namespace {

// Calls fn(storage index) for every particle in persistent-id order.
template <typename F>
void ForEachById(const Particles& p, int64_t next_id, F fn) {
  std::vector<int32_t> index(next_id, -1);
  for (size_t i = 0; i < p.size(); ++i) index[p.id[i]] = static_cast<int32_t>(i);
  for (int64_t id = 0; id < next_id; ++id)
    if (index[id] >= 0) fn(static_cast<size_t>(index[id]));
}

}  // namespace

double System::KineticEnergy() const {
  // The sum in persistent-id order of the particles' terms. A particle at rest (v = w = 0, every
  // sleeper) adds exactly +0 to a sum of terms >= 0, so only the others are summed, in that
  // order: the same bits, without walking a sleeping bed in id order at every output row.
  std::vector<std::pair<int64_t, int32_t>> moving;  // (id, storage index)
  for (size_t i = 0; i < p_.size(); ++i) {
    const bool at_rest = Norm2(p_.v[i]) == 0.0 && Norm2(p_.w[i]) == 0.0 &&
                         std::isfinite(p_.mass[i]) && std::isfinite(0.5 / p_.inv_inertia[i]);
    if (!at_rest) moving.emplace_back(p_.id[i], static_cast<int32_t>(i));
  }
  std::sort(moving.begin(), moving.end());
  double e = 0;
  for (const auto& [id, i] : moving) {
    if (clumps_.ClumpOf(id) >= 0) continue;
    e += 0.5 * p_.mass[i] * Norm2(p_.v[i]) + 0.5 / p_.inv_inertia[i] * Norm2(p_.w[i]);
  }
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
  const internal::Workspace& m = *ws_;
  const int nm = materials_.size();
  double e = 0;
  if (m.stale.list) return 0;
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
  // Bonds, only when there are any (an unbonded run hashes as it did before bonds).
  ws_->bond.Sync();
  for (const Bond& b : ws_->bond.bonds) {
    mix(&b.a, sizeof(int64_t));
    mix(&b.b, sizeof(int64_t));
    const uint8_t intact = b.intact;
    mix(&intact, 1);
    mix(&b.fn, sizeof(double));
    mix(&b.fs, sizeof(Vec3));
    mix(&b.mt, sizeof(double));
    mix(&b.mb, sizeof(Vec3));
  }
  return h;
}

}  // namespace dem

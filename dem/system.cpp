// The System: the public facade of the dem module. It owns the particles and the configuration
// and runs the step's phases (dem/internal_phases.h) over its workspace in order; the phases
// themselves live in one file each. The clump API is in dem/clump.cpp, the totals and the state
// hash in dem/totals.cpp.
#include "dem/system.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "dem/contact.h"
#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem {

System::System(MaterialTable materials, SystemConfig config)
    : materials_(std::move(materials)),
      config_(std::move(config)),
      ws_(std::make_unique<internal::Workspace>()) {
  internal::Workspace& m = *ws_;
  const int nm = materials_.size();
  m.pair.resize(nm * nm);
  for (int a = 0; a < nm; ++a)
    for (int b = 0; b < nm; ++b)
      m.pair[a * nm + b] =
          MakePairConstants(materials_[a], materials_[b], materials_.interaction(a, b));
  const int np = static_cast<int>(config_.planes.size());
  m.wall.resize(nm * np);
  for (int a = 0; a < nm; ++a)
    for (int k = 0; k < np; ++k) {
      const int wm = config_.planes[k].material;
      m.wall[a * np + k] =
          MakePairConstants(materials_[a], materials_[wm], materials_.interaction(a, wm));
    }
  plane_force_.assign(np, Vec3{});
  m.skin = config_.skin;
  m.near_skin = std::max(0.0, config_.near_fraction * config_.skin);  // never below contact
  num_threads_ = omp_get_max_threads();
}

System::~System() = default;

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
  ws_->stale.rebuild = true;
  ws_->stale.active = true;  // existing list indices stay valid: new particles come last
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
  internal::Workspace& m = *ws_;
  m.stale.active = true;
  for (internal::MeshState& ms : m.meshes) {
    size_t kept = 0;
    for (const internal::MeshHistory& h : ms.history)
      if (!gone[h.id]) ms.history[kept++] = h;
    ms.history.resize(kept);
  }
  m.pending = std::move(keep);
  m.stale.list = true;
  m.stale.rebuild = true;
  clumps_.Reindex(p_, next_id_);
  // Their bonds go with them.
  internal::BondWork& bw = m.bond;
  if (!bw.bonds.empty()) {
    bw.Sync();
    size_t kept = 0;
    for (const Bond& b : bw.bonds)
      if (!gone[b.a] && !gone[b.b]) bw.bonds[kept++] = b;
    bw.bonds.resize(kept);
    bw.stale = true;
  }
}

void System::Touch() {
  ws_->stale.rebuild = true;
  // The config's skins (a state restored under another neighbour config takes them here).
  ws_->skin = config_.skin;
  ws_->near_skin = std::max(0.0, config_.near_fraction * config_.skin);
}

NeighborStats System::neighbor_stats() const {
  const internal::Workspace& m = *ws_;
  NeighborStats s;
  s.builds = builds_;
  s.partial_builds = m.partial_builds;
  s.near_builds = m.near_builds;
  s.near_pairs = m.near_pairs;
  s.pairs = static_cast<int64_t>(m.list.num_pairs());
  s.contacts = m.contacts;
  s.wall_contacts = m.wall_contacts;
  s.mesh_contacts = m.mesh_contacts;
  s.awake = config_.sleep.enabled ? m.awake : static_cast<int64_t>(p_.size());
  s.max_overlap = m.max_overlap;
  return s;
}

// The contact history (list pairs, walls, then pending records), sorted by (a, b).
std::vector<ContactRecord> System::Contacts() const {
  std::vector<ContactRecord> out;
  internal::FlushNear(*ws_, num_threads_);  // moves history only: the state is unchanged
  const internal::Workspace& m = *ws_;
  out.reserve(static_cast<size_t>(m.contacts + m.wall_contacts) + m.pending.size());
  if (!m.stale.list) {
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
  ws_->pending = contacts;
  ws_->stale.list = true;
  ws_->stale.rebuild = true;
}

void System::Rebuild(int nt) {
  internal::Rebuild(*ws_, p_, clumps_, config_, next_id_, nt);
  ws_->bond.stale = true;  // the bonds' storage indices
  ++builds_;
}

void System::set_num_threads(int n) {
  num_threads_ = n;
  if (governor_) governor_ = std::make_unique<ThreadGovernor>(n, governor_config_);
}

void System::set_adaptive_threads(bool on, const GovernorConfig& config) {
  governor_config_ = config;
  governor_ = on ? std::make_unique<ThreadGovernor>(num_threads_, config) : nullptr;
}

// One step of velocity Verlet (LIGGGHTS fix nve/sphere; Allen & Tildesley eq. 3.19): half kick
// and drift, the neighbour list made again if the drift asks for it, the forces (pairs and
// planes, then meshes), the second half kick, the sleep checks and the health checks. Each phase
// is a function of dem/internal_phases.h; the time each takes goes to phase_times_.
StepStatus System::Step(const std::function<void()>& motion) {
  internal::Workspace& m = *ws_;
  const double dt = config_.time_step;
  const bool sleeping = config_.sleep.enabled;
  const bool have_clumps = !clumps_.empty();
  // This step's worker count: the governor's with adaptive threads (results do not depend on it).
  const int nt = governor_ ? governor_->threads() : num_threads_;
  double t_phase = internal::Now();
  const double t_step = t_phase;
  auto lap = [&t_phase](double& phase) {  // adds the time since the last lap to `phase`
    const double now = internal::Now();
    phase += now - t_phase;
    t_phase = now;
  };
  // First half kick and drift (with sleeping, of the awake particles only).
  if (sleeping && m.stale.active) internal::RefreshActive(m, p_, nt);
  lap(phase_times_.sleep);
  // The clump of each storage index: KickDrift leaves a clump's spheres to it.
  const int32_t* clump_of = clumps_.clump_of_index(p_.size());
  double max_v2 = internal::KickDrift(m, p_, config_, nt, clump_of);
  if (have_clumps) {  // rigid clumps (dem/clump.h): move the bodies, place their spheres
    // With clump_of, each sphere KickDrift left is placed, its 1/|w| with it; without, the spins
    // were set after the kick and the force pass makes them.
    double* inv_spin = clump_of != nullptr && m.inv_spin_kicked ? m.inv_spin.data() : nullptr;
    // With sleeping, the active list (made above) holds every awake sphere: a waking clump has one.
    const ClumpSet::BeginReport r =
        clumps_.BeginStep(p_, dt, nt, m.moved.size() == p_.size() ? m.moved.data() : nullptr,
                          inv_spin, sleeping && !m.stale.active ? &m.active : nullptr);
    m.inv_spin_kicked = inv_spin != nullptr;
    max_v2 = std::max(max_v2, r.max_member_speed2);
    if (r.woke) {  // their pairs are listed: only the visiting lists change
      m.stale.busy = true;
      m.stale.active = true;
    }
  }
  const bool rebuild = internal::NeedsRebuild(m, p_, dt * std::sqrt(max_v2), sleeping, nt);
  lap(phase_times_.integrate);
  if (rebuild) {
    Rebuild(nt);
    lap(phase_times_.rebuild);
  }

  // Forces.
  internal::ComputeForces(m, p_, config_, materials_.size(), nt, &phase_times_, &plane_force_,
                          motion);  // adds its own phases (near, pairs); calls `motion`
  t_phase = internal::Now();
  if (!m.meshes.empty()) {
    internal::MeshForces(m, p_, dt, config_.mesh_rolling_torque, nt);
    lap(phase_times_.mesh);
  }
  // Bonds (dem/bond.h), before the second kick: a clump's EndStep sums its spheres' bond forces.
  if (!m.bond.bonds.empty()) {
    internal::BondForces(m, p_, config_.sleep, dt, time_ + dt, nt);
    lap(phase_times_.bonds);
  }

  // Second half kick (a mesh may have woken particles).
  if (sleeping && m.stale.active) internal::RefreshActive(m, p_, nt);
  lap(phase_times_.sleep);
  max_v2 = 0;
  bool finite = internal::Kick(m, p_, dt, sleeping, nt, &max_v2);
  if (have_clumps && !clumps_.EndStep(p_, config_.gravity, dt, nt)) finite = false;
  time_ += dt;
  ++step_count_;
  lap(phase_times_.integrate);

  // Sleep and wake checks.
  if (sleeping && ++m.sleep_counter >= config_.sleep.check_every) {
    m.sleep_counter = 0;
    internal::UpdateSleep(m, p_, config_.sleep, nt);
    if (have_clumps && clumps_.SyncSleep(p_, config_.sleep.quiet_checks)) {
      m.stale.active = true;  // a clump sleeps as a unit
      m.stale.busy = true;
    }
    lap(phase_times_.sleep);
  }
  if (governor_) governor_->Record(internal::Now() - t_step, rebuild);
  return internal::CheckHealth(m, p_, config_, time_, finite, max_v2);
}

// ---------------------------------------------------------------------------------------------
// Triangle-mesh walls (dem/mesh_contact.cpp).

// The clump API (dem/clump.h holds the clump maths; System::AddClump is in clump.cpp, under its
// compile flags, see there).
int System::AddClumpTemplate(const ClumpTemplate& t) { return clumps_.AddShape(t); }
int System::num_clump_templates() const { return static_cast<int>(clumps_.shapes().size()); }
const ClumpShape& System::clump_shape(int k) const { return clumps_.shapes()[k]; }
const Clumps& System::clumps() const { return clumps_.state(); }
Clumps& System::mutable_clumps() { return clumps_.mutable_state(); }
int64_t System::num_bodies() const {
  const Clumps& c = clumps_.state();
  return static_cast<int64_t>(p_.size() - c.member.size() + c.size());
}

int System::AddMesh(TriangleMesh mesh) {
  ws_->meshes.push_back(internal::MakeMeshState(std::move(mesh), materials_));
  return static_cast<int>(ws_->meshes.size()) - 1;
}

int System::num_meshes() const { return static_cast<int>(ws_->meshes.size()); }
const TriangleMesh& System::mesh(int k) const { return ws_->meshes[k].mesh; }
const MeshMotion& System::mesh_motion(int k) const { return ws_->meshes[k].motion; }
MeshWrench System::mesh_wrench(int k) const { return ws_->meshes[k].wrench; }

void System::SetMeshMotion(int k, const MeshMotion& motion) {
  internal::MoveMesh(ws_->meshes[k], motion);
}

// ---------------------------------------------------------------------------------------------
// Bonds (dem/bond.h; the phase is in dem/bond.cpp).

void System::AddBonds(const std::vector<Bond>& bonds) {
  // Every bond is checked before any is added.
  std::vector<int32_t> index(next_id_, -1);
  for (size_t i = 0; i < p_.size(); ++i) index[p_.id[i]] = static_cast<int32_t>(i);
  ws_->bond.Sync();
  std::vector<std::pair<int64_t, int64_t>> pairs;
  pairs.reserve(ws_->bond.bonds.size() + bonds.size());
  for (const Bond& b : ws_->bond.bonds) pairs.emplace_back(b.a, b.b);
  std::sort(pairs.begin(), pairs.end());
  const size_t existing = pairs.size();
  std::vector<Bond> add = bonds;
  for (size_t k = 0; k < add.size(); ++k) {
    Bond& b = add[k];
    const auto fail = [&](const std::string& why) {
      throw std::invalid_argument("AddBonds: bond " + std::to_string(k) + " (" +
                                  std::to_string(b.a) + ", " + std::to_string(b.b) + "): " + why);
    };
    const auto known = [&](int64_t id) { return id >= 0 && id < next_id_ && index[id] >= 0; };
    if (!known(b.a) || !known(b.b)) fail("unknown particle id");
    if (b.a >= b.b) fail(b.a == b.b ? "a sphere bonded to itself" : "ids not in order (a < b)");
    const int32_t ca = clumps_.ClumpOf(b.a);
    if (ca >= 0 && ca == clumps_.ClumpOf(b.b))
      fail("both spheres belong to clump " + std::to_string(ca));
    if (std::binary_search(pairs.begin(), pairs.begin() + existing, std::make_pair(b.a, b.b)))
      fail("bonded already");
    if (!(b.radius > 0 && std::isfinite(b.radius))) fail("radius must be > 0");
    if (!(b.kn > 0 && std::isfinite(b.kn) && b.ks > 0 && std::isfinite(b.ks)))
      fail("kn and ks must be > 0");
    if (!(b.tensile_strength > 0 && b.cohesion > 0)) fail("strengths must be > 0");
    if (!(b.tan_friction >= 0 && std::isfinite(b.tan_friction))) fail("tan_friction must be >= 0");
    if (!(b.damping_ratio >= 0 && std::isfinite(b.damping_ratio)))
      fail("damping_ratio must be >= 0");
    if (Norm2(b.normal) == 0.0) {
      const Vec3 d = p_.x[index[b.b]] - p_.x[index[b.a]];
      if (!(Norm2(d) > 0.0)) fail("the spheres' centres coincide");
      b.normal = (1.0 / Norm(d)) * d;
    }
    pairs.emplace_back(b.a, b.b);
  }
  // Pairs repeated within the new bonds.
  std::sort(pairs.begin() + existing, pairs.end());
  const auto twice = std::adjacent_find(pairs.begin() + existing, pairs.end());
  if (twice != pairs.end())
    throw std::invalid_argument("AddBonds: (" + std::to_string(twice->first) + ", " +
                                std::to_string(twice->second) + ") bonded twice");
  internal::BondWork& bw = ws_->bond;
  bw.bonds.insert(bw.bonds.end(), add.begin(), add.end());
  bw.stale = true;
}

const std::vector<Bond>& System::bonds() const {
  ws_->bond.Sync();  // the state only moves from the pass's copy into the record
  return ws_->bond.bonds;
}

int64_t System::bond_count() const { return static_cast<int64_t>(ws_->bond.bonds.size()); }

int64_t System::intact_bond_count() const {
  // While the bond pass's index is current its live list is the intact bonds; after a step that
  // broke some (or any other change) they are counted from the record.
  if (!ws_->bond.stale) return static_cast<int64_t>(ws_->bond.live.size());
  ws_->bond.Sync();
  int64_t n = 0;
  for (const Bond& b : ws_->bond.bonds) n += b.intact;
  return n;
}

std::vector<BondBreak> System::TakeBondBreaks() {
  std::vector<BondBreak> out;
  out.swap(ws_->bond.breaks);
  return out;
}

double System::BondEnergy() const {
  ws_->bond.Sync();
  double e = 0;
  for (const Bond& b : ws_->bond.bonds)
    if (b.intact) e += dem::BondEnergy(b);
  return e;
}

// A cell search: cells of 2 r_max + gap, each particle against the particles of its own and the
// 26 neighbouring cells (keys sorted, found by binary search).
std::vector<std::pair<int64_t, int64_t>> System::PairsWithinGap(double gap) const {
  if (!(gap >= 0 && std::isfinite(gap)))
    throw std::invalid_argument("PairsWithinGap: gap must be >= 0, got " + std::to_string(gap));
  std::vector<std::pair<int64_t, int64_t>> out;
  const size_t n = p_.size();
  if (n < 2) return out;
  double r_max = 0;
  Vec3 lo = p_.x[0];
  for (size_t i = 0; i < n; ++i) {
    r_max = std::max(r_max, p_.radius[i]);
    lo = Vec3{std::min(lo.x, p_.x[i].x), std::min(lo.y, p_.x[i].y), std::min(lo.z, p_.x[i].z)};
  }
  const double cell = 2 * r_max + gap;
  const auto coord = [&](double x, double l) { return static_cast<int64_t>((x - l) / cell); };
  const int64_t span = 1 << 20;  // cells per axis in the key (21 bits each)
  const auto key = [&](int64_t cx, int64_t cy, int64_t cz) { return (cx * span + cy) * span + cz; };
  std::vector<std::pair<int64_t, int32_t>> keyed(n);
  for (size_t i = 0; i < n; ++i)
    keyed[i] = {key(coord(p_.x[i].x, lo.x), coord(p_.x[i].y, lo.y), coord(p_.x[i].z, lo.z)),
                static_cast<int32_t>(i)};
  std::sort(keyed.begin(), keyed.end());
  for (size_t i = 0; i < n; ++i) {
    const int64_t cx = coord(p_.x[i].x, lo.x), cy = coord(p_.x[i].y, lo.y),
                  cz = coord(p_.x[i].z, lo.z);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          if (cx + dx < 0 || cy + dy < 0 || cz + dz < 0) continue;
          const int64_t k = key(cx + dx, cy + dy, cz + dz);
          auto it = std::lower_bound(keyed.begin(), keyed.end(), std::make_pair(k, int32_t{-1}));
          for (; it != keyed.end() && it->first == k; ++it) {
            const size_t j = static_cast<size_t>(it->second);
            if (p_.id[j] <= p_.id[i]) continue;  // each pair once, from its lower id
            const double reach = p_.radius[i] + p_.radius[j] + gap;
            if (Norm2(p_.x[j] - p_.x[i]) >= reach * reach) continue;
            const int32_t ci = clumps_.ClumpOf(p_.id[i]);
            if (ci >= 0 && ci == clumps_.ClumpOf(p_.id[j])) continue;
            out.emplace_back(p_.id[i], p_.id[j]);
          }
        }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// ---------------------------------------------------------------------------------------------
// Sleeping (dem/sleep.cpp).

void System::set_sleep(const SleepConfig& sleep) {
  config_.sleep = sleep;
  if (!sleep.enabled) internal::WakeAll(p_);
  ws_->stale.rebuild = true;  // the list and the busy particles depend on sleeping
  ws_->stale.active = true;
}

int64_t System::awake_count() const {
  int64_t n = 0;
  for (uint8_t a : p_.awake) n += a != 0;
  return n;
}

}  // namespace dem

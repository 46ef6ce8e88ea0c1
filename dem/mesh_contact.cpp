// Particle-mesh contacts: the moving triangle-mesh walls (the scoop), their candidate lists and
// their contact forces, with the wrench the particles exert on each mesh.
#include <algorithm>
#include <cmath>

#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"
#include "dem/triangle.h"

namespace dem::internal {

MeshState MakeMeshState(TriangleMesh mesh, const MaterialTable& materials) {
  MeshState ms;
  const int nm = materials.size();
  ms.constants.resize(nm);
  for (int a = 0; a < nm; ++a)
    ms.constants[a] = MakePairConstants(materials[a], materials[mesh.material],
                                        materials.interaction(a, mesh.material));
  for (const Vec3& v : mesh.vertices) ms.reach = std::max(ms.reach, Norm(v));
  ms.world = mesh.vertices;
  ms.mesh = std::move(mesh);
  return ms;
}

void MoveMesh(MeshState& ms, const MeshMotion& motion) {
  ms.motion = motion;
  const Pose& pose = motion.pose;
  for (size_t a = 0; a < ms.mesh.vertices.size(); ++a)
    ms.world[a] = Apply(pose, ms.mesh.vertices[a]);
}

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

namespace {

constexpr int kMaxHits = 16;     // touching triangles looked at per particle
constexpr int kMaxContacts = 4;  // contacts kept per particle and mesh
// Below this many candidate groups (particles near a mesh) the contacts are evaluated on one
// thread: a group costs well under a microsecond, a wake-up of sleeping OpenMP threads tens.
constexpr int kParallelGroups = 1024;

// Candidates of a mesh: every (particle, triangle) pair closer than r + skin now. They stay valid
// while the mesh's largest vertex displacement plus the particles' largest displacement since
// the build stays below the skin (checked in MeshForces).
void BuildMeshCandidates(Workspace& m, const Particles& p, MeshState& ms) {
  const size_t n = p.size();
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
    const Vec3 c = p.x[i];
    const double reach = p.radius[i] + m.skin;
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

// Drops the candidates of a mesh when the mesh's largest vertex displacement since their build
// plus the particles' (bounded by particle_drift) may have reached 0.9 skin.
void CheckCandidates(MeshState& ms, double skin) {
  if (!ms.candidates_valid) return;
  const Pose& pose = ms.motion.pose;
  const Quat dq = pose.orientation * Conjugate(ms.pose_build.orientation);
  const double angle =
      2.0 * std::atan2(std::sqrt(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z), std::abs(dq.w));
  const double moved = Norm(pose.position - ms.pose_build.position) + angle * ms.reach;
  if (!(moved + ms.particle_drift < 0.9 * skin)) ms.candidates_valid = false;
}

// Sizes the per-group results and finds each group's stored history (both lists are sorted by
// particle storage index).
void PrepareGroups(MeshState& ms) {
  const int ng = static_cast<int>(ms.group_particle.size());
  ms.group_force.resize(ng);
  ms.group_torque.resize(ng);
  ms.group_mesh_torque.resize(ng);
  ms.group_overlap.assign(ng, 0.0);
  ms.group_new.assign(ng, 0);
  ms.group_history.resize(ng + 1);
  ms.fresh.resize(static_cast<size_t>(kMaxContacts) * ng);
  size_t h = 0;
  for (int g = 0; g < ng; ++g) {
    while (h < ms.history.size() && ms.history[h].index < ms.group_particle[g]) ++h;
    ms.group_history[g] = static_cast<int32_t>(h);
  }
  ms.group_history[ng] = static_cast<int32_t>(ms.history.size());
}

// Contacts of candidate group g (one particle) with the mesh, into the group's results and its
// fresh history slots; the rolling couples count in the mesh's torque when rolling_on_mesh.
// Returns the deepest overlap / diameter.
double GroupContacts(MeshState& ms, const Particles& p, int g, double dt, bool rolling_on_mesh) {
  const Vec3 origin = ms.motion.pose.position, vel = ms.motion.velocity;
  const Vec3 omega = ms.motion.angular_velocity;
  const auto& tris = ms.mesh.triangles;
  const int ng = static_cast<int>(ms.group_particle.size());
  const int32_t i = ms.group_particle[g];
  const Vec3 c = p.x[i];
  const double r = p.radius[i];
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
  double worst = 0;
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
    const Vec3 v_rel = v_mesh - (p.v[i] + r * Cross(p.w[i], nrm));
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
        EvaluateWallContact(ms.constants[p.material[i]], nrm, delta, r, p.mass[i], v_rel, p.w[i],
                            omega, p.inv_inertia[i], dt, shear);
    const Vec3 fa = cf.ft - cf.fn * nrm;  // on the particle
    fi += fa;
    ti += r * Cross(nrm, cf.ft) + cf.mr;
    tm += Cross(hit.point - origin, -fa);
    if (rolling_on_mesh) tm -= cf.mr;
    ms.fresh[static_cast<size_t>(kMaxContacts) * g + nk] = {i, p.id[i], nrm, shear};
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
  return worst;
}

// Sums the groups of mesh k in group order (fixed by the data: deterministic whatever the thread
// count): forces onto the particles, the wrench onto the mesh, the fresh history in place of the
// old. A sleeping particle the mesh touched wakes.
void SumGroups(Workspace& m, Particles& p, int k) {
  MeshState& ms = m.meshes[k];
  const int ng = static_cast<int>(ms.group_particle.size());
  MeshWrench wrench;
  ms.history.clear();
  for (int g = 0; g < ng; ++g) {
    if (ms.group_new[g] == 0) continue;
    const int32_t i = ms.group_particle[g];
    if (ms.group_overlap[g] > m.mesh_worst) {
      m.mesh_worst = ms.group_overlap[g];
      m.mesh_worst_id = p.id[i];
      m.mesh_worst_mesh = k;
    }
    p.f[i] += ms.group_force[g];
    p.t[i] += ms.group_torque[g];
    wrench.force -= ms.group_force[g];
    wrench.torque += ms.group_mesh_torque[g];
    wrench.contacts += ms.group_new[g];
    for (int a = 0; a < ms.group_new[g]; ++a)
      ms.history.push_back(ms.fresh[static_cast<size_t>(kMaxContacts) * g + a]);
    if (!p.awake[i]) {  // a mesh touched a sleeping particle: wake it (its pairs are listed)
      p.awake[i] = 1;
      p.f[i] = ms.group_force[g];  // at rest in equilibrium but for the mesh's push
      p.t[i] = ms.group_torque[g];
      m.stale.busy = true;
      m.stale.active = true;
    }
  }
  ms.wrench = wrench;
}

}  // namespace

// Particle-mesh contacts (Hertz-Mindlin, dem/contact.h, with the particle-mesh interaction; the
// mesh is rigid and kinematic, so R* = r and m* = m). A sphere may touch several triangles; to
// count a flat region, a shared edge or a shared vertex once, the touching triangles are taken
// nearest first and a further one is kept only if its closest point lies strictly above the
// tangent plane of every contact kept so far. On a flat or convex patch all closest points lie
// in (or below) that plane and only the nearest counts; in a concave corner the second face
// rises above it and is a second, genuine contact.
void MeshForces(Workspace& m, Particles& p, double dt, bool rolling_on_mesh, int nt) {
  int64_t total = 0;
  double worst_overlap = 0;
  m.mesh_worst = 0;
  m.mesh_worst_id = -1;
  for (int k = 0; k < static_cast<int>(m.meshes.size()); ++k) {
    MeshState& ms = m.meshes[k];
    CheckCandidates(ms, m.skin);
    if (!ms.candidates_valid) BuildMeshCandidates(m, p, ms);
    PrepareGroups(ms);
    const int ng = static_cast<int>(ms.group_particle.size());
    double worst = 0;
    // A scoop touches hundreds of particles: fewer groups than kParallelGroups cost less than
    // waking the other threads (results are the same either way).
#pragma omp parallel for schedule(static) num_threads(nt) \
    reduction(max                                         \
              : worst) if (ng >= kParallelGroups)
    for (int g = 0; g < ng; ++g)
      worst = std::max(worst, GroupContacts(ms, p, g, dt, rolling_on_mesh));
    SumGroups(m, p, k);
    total += ms.wrench.contacts;
    worst_overlap = std::max(worst_overlap, worst);
  }
  m.mesh_contacts = total;
  m.max_overlap = std::max(m.max_overlap, worst_overlap);
}

}  // namespace dem::internal

// System::SaveState and RestoreState: the whole mutable state of the step, field by field,
// through one list (StateFields) that saves and loads alike (dem/archive.h). Scratch arrays are
// kept too: whatever the step keeps between calls comes back as it was, so a restored System
// steps on bit for bit without reasoning about which arrays a step reads before it writes them.
#include <string>

#include "dem/archive.h"
#include "dem/internal_workspace.h"
#include "dem/system.h"

namespace dem {
namespace {

// Names the layout; change it with any change to StateFields. Version 2 added the bonds at the
// end (BondFields); a version 1 state (no bonds) is still read.
constexpr char kStateFormat[] = "scoopsim dem state 2";
constexpr char kStateFormatNoBonds[] = "scoopsim dem state 1";

template <typename Archive>
void ParticleFields(Archive& a, Particles& p) {
  a(p.id);
  for (auto* v : {&p.x, &p.v, &p.w, &p.f, &p.t}) a(*v);
  for (auto* v : {&p.radius, &p.mass, &p.inv_mass, &p.inv_inertia}) a(*v);
  a(p.material);
  a(p.awake);
}

template <typename Archive>
void MeshFields(Archive& a, internal::MeshState& m) {
  a(m.motion);
  a(m.world);
  a(m.reach);
  for (auto* v : {&m.group_particle, &m.group_start, &m.cand_tri}) a(*v);
  a(m.candidates_valid);
  a(m.pose_build);
  a(m.particle_drift);
  a(m.history);
  for (auto* v : {&m.group_force, &m.group_torque, &m.group_mesh_torque}) a(*v);
  a(m.group_overlap);
  for (auto* v : {&m.group_history, &m.group_new}) a(*v);
  a(m.fresh);
  a(m.wrench);
}

template <typename Archive>
void WorkspaceFields(Archive& a, internal::Workspace& m) {
  a(m.stale);
  a(m.skin);
  m.list.Fields(a);
  a(m.shear);
  a(m.touching);
  a(m.x_build);
  a(m.drift_bound);
  a(m.moved);
  a(m.asleep_drift);
  a(m.particle_material);
  a(m.alike);
  for (auto* v : {&m.near_k, &m.near_j}) a(*v);
  a(m.near_shear);
  a(m.near_touch);
  for (auto* v : {&m.near_off, &m.near_count, &m.scratch_near_k}) a(*v);
  a(m.near_skin);
  a(m.near_bound);
  a(m.near_builds);
  a(m.near_pairs);
  a(m.slab_weight);
  for (auto* v : {&m.wall_start, &m.wall_i, &m.wall_k}) a(*v);
  a(m.wall_shear);
  a(m.slab_plane_force);
  for (auto* v : {&m.wall_visit, &m.slab_wall_visit}) a(*v);
  for (internal::MeshState& mesh : m.meshes) MeshFields(a, mesh);
  a(m.mesh_contacts);
  a(m.mesh_worst);
  a(m.mesh_worst_id);
  a(m.mesh_worst_mesh);
  a(m.awake);
  a(m.sleep_counter);
  for (auto* v : {&m.active, &m.busy, &m.slab_busy}) a(*v);
  for (auto* v : {&m.scratch_busy, &m.scratch_slab_awake}) a(*v);
  a(m.pending);
  for (auto* v : {&m.old_start, &m.old_partner, &m.old_wall_start, &m.old_wall_k}) a(*v);
  for (auto* v : {&m.old_shear, &m.old_wall_shear}) a(*v);
  a(m.old_touching);
  for (auto* v : {&m.perm, &m.visit, &m.index_of_id, &m.new_of_old}) a(*v);
  a(m.scratch_d);
  a(m.scratch_i64);
  a(m.scratch_i32);
  a(m.scratch_v);
  for (auto* v : {&m.scratch_u8, &m.scratch_wake, &m.scratch_zone}) a(*v);
  a(m.slab_overlap);
  for (auto* v : {&m.slab_contacts, &m.slab_wall_contacts}) a(*v);
  a(m.contacts);
  a(m.wall_contacts);
  a(m.max_overlap);
}

// The bonds and the breaks not yet taken; the rest of Workspace::bond is made again from them.
template <typename Archive>
void BondFields(Archive& a, internal::BondWork& w) {
  w.Sync();  // saving: the latest state; loading: the copy is dropped below
  a(w.bonds);
  a(w.breaks);
  w.stale = true;
}

}  // namespace

template <typename Archive>
void System::StateFields(Archive& a) {
  ParticleFields(a, p_);
  clumps_.Fields(a);
  a(plane_force_);
  a(time_);
  a(step_count_);
  a(next_id_);
  a(builds_);
  a(config_.sleep);
  WorkspaceFields(a, *ws_);
}

std::vector<char> System::SaveState() const {
  ArchiveWriter a;
  a(std::string(kStateFormat));
  // The clump templates (their shapes are made again from them) and the mesh count.
  a(static_cast<uint64_t>(clumps_.shapes().size()));
  for (const ClumpShape& s : clumps_.shapes()) {
    a(s.source.name);
    a(s.source.centers);
    a(s.source.radii);
  }
  a(static_cast<uint64_t>(ws_->meshes.size()));
  const_cast<System*>(this)->StateFields(a);  // reads only
  BondFields(a, ws_->bond);  // marks the bonds' index stale: it is made again alike
  return a.bytes();
}

void System::RestoreState(const std::vector<char>& bytes) {
  ArchiveReader a(bytes);
  std::string format;
  a(format);
  const bool bonds = format == kStateFormat;
  if (!bonds && format != kStateFormatNoBonds)
    throw std::runtime_error("state: format '" + format + "', expected '" + kStateFormat + "'");
  uint64_t shapes = 0;
  a(shapes);
  for (uint64_t k = 0; k < shapes; ++k) {
    ClumpTemplate t;
    a(t.name);
    a(t.centers);
    a(t.radii);
    if (clumps_.AddShape(t) != static_cast<int>(k))
      throw std::runtime_error("state: the clump templates differ from the system's");
  }
  uint64_t meshes = 0;
  a(meshes);
  if (meshes != ws_->meshes.size())
    throw std::runtime_error("state: " + std::to_string(meshes) + " meshes, the system has " +
                             std::to_string(ws_->meshes.size()));
  StateFields(a);
  if (bonds) {
    BondFields(a, ws_->bond);
  } else {
    ws_->bond = internal::BondWork{};
  }
  ws_->bond.hot_ahead = false;  // (BondFields marked the bonds' index stale)
  ws_->near_owners = false;     // made again from the restored near list (ListSlotOwners)
  if (!a.done()) throw std::runtime_error("state: bytes left over");
}

}  // namespace dem

// Private to dem/: nothing outside dem/ includes this header. The phases of System::Step, as
// plain functions over the Workspace (dem/internal_workspace.h) and the System's own particles
// and configuration, grouped by the file that defines them, in the order a step runs them.
// `nt` is the number of worker threads; results never depend on it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "dem/system.h"

namespace dem::internal {

struct Workspace;
struct MeshState;

// --- dem/integrate.cpp: velocity Verlet -------------------------------------------------------

// First half kick and drift of every moving particle (the awake ones with sleeping: the caller
// refreshes Workspace::active first); starts this step's force with gravity and the torque at
// zero. Returns the largest |v|^2 after the kick [m^2/s^2]. `clump_of` (the clump of each storage
// index, -1 for a single sphere; or null): a clump's sphere only counts in that |v|^2, since
// ClumpSet::BeginStep sets its x, v, w, f and t next (and its 1/|w|).
double KickDrift(Workspace& m, Particles& p, const SystemConfig& config, int nt,
                 const int32_t* clump_of);
// Adds step_bound (dt max |v| of this step) to the drift bounds of the neighbour list, the near
// list and the mesh candidates, marks the near list stale when it may have been outrun, and says
// whether the neighbour list must be built again (some particle may have moved skin / 2).
bool NeedsRebuild(Workspace& m, const Particles& p, double step_bound, bool sleeping, int nt);
// Second half kick of every moving particle. Returns whether every v and w is finite; the largest
// |v|^2 goes to *max_v2.
bool Kick(const Workspace& m, Particles& p, double dt, bool sleeping, int nt, double* max_v2);

// --- dem/neighbor_build.cpp: the neighbour list ------------------------------------------------

// Reorders storage by cell, builds the half list and the plane candidates again and carries the
// contact history over (pair, plane and mesh history follow their particles; pending records are
// applied). Clears Stale::rebuild and Stale::list, marks everything made from the list stale.
void Rebuild(Workspace& m, Particles& p, ClumpSet& clumps, const SystemConfig& config,
             int64_t next_id, int nt);

// --- dem/near_list.cpp: the lists the force pass walks ------------------------------------------

// Puts the near slots' history back into the list's arrays (Stale::list_history).
void FlushNear(Workspace& m, int nt);
// Lists the particles the force pass visits with sleeping on (Workspace::busy).
void RefreshBusy(Workspace& m, const Particles& p, int nt);
// Lists the visited particles with plane candidates, slab by slab (Workspace::wall_visit);
// compact: the visited particles are the busy ones.
void ListWallVisits(Workspace& m, bool compact, int nt);
// Makes the near list (Workspace::near_k) and the force pass's slab order.
void BuildNear(Workspace& m, const Particles& p, bool sleeping, int nt);
// Makes Workspace::near_i and slab_slot for the present near list (after BuildNear, or after a
// restored state brought its near list without them).
void ListSlotOwners(Workspace& m, const Particles& p, bool sleeping, int nt);

// --- dem/force_pass.cpp: particle-particle and particle-plane contacts -------------------------

// Adds the contact forces and torques to p.f and p.t (which hold gravity already), refreshing the
// stale lists first; the force on each plane goes to plane_force (num_planes). nm: number of
// materials. Adds its time to times->near and times->pairs. `motion` (System::Step's, may be
// empty) is called once, by the last of the nt threads before it takes its slabs (the others take
// them meanwhile); on one thread its time is left out of times->pairs.
void ComputeForces(Workspace& m, Particles& p, const SystemConfig& config, int nm, int nt,
                   PhaseTimes* times, std::vector<Vec3>* plane_force,
                   const std::function<void()>& motion);

// --- dem/mesh_contact.cpp: triangle-mesh walls -------------------------------------------------

// A mesh with its contact constants against each particle material, at rest at the origin.
MeshState MakeMeshState(TriangleMesh mesh, const MaterialTable& materials);
// Sets the mesh's pose and twist and places its vertices in the world.
void MoveMesh(MeshState& ms, const MeshMotion& motion);
// Particle-mesh contacts of every mesh into p.f, p.t and the mesh wrenches (the rolling couples
// counted in a mesh's torque when rolling_on_mesh); wakes the sleeping particles a mesh touches.
void MeshForces(Workspace& m, Particles& p, double dt, bool rolling_on_mesh, int nt);
// World bounding box of each triangle grown by `margin` (lo at 2e, hi at 2e + 1), and the box
// around them all.
void TriangleBoxes(const std::vector<Vec3>& world, const std::vector<std::array<int32_t, 3>>& tris,
                   double margin, std::vector<Vec3>* box, Vec3* all_lo, Vec3* all_hi);
// Whether c lies within the box [lo, hi] grown by d.
inline bool InBox(const Vec3& c, const Vec3& lo, const Vec3& hi, double d) {
  return !(c.x < lo.x - d || c.x > hi.x + d || c.y < lo.y - d || c.y > hi.y + d || c.z < lo.z - d ||
           c.z > hi.z + d);
}

// --- dem/bond.cpp: breakable bonds --------------------------------------------------------------

// The bonds' forces and torques into p.f and p.t (awake particles only), after the contacts: each
// live bond on its own (in parallel, its own result slots), then each particle sums its bonds in
// bond order. Breaks go to Workspace::bond.breaks with time t_end; a break wakes both ends, an end
// awake and faster than sleep.wake_speed wakes the other (sleeping on). A bond between two
// sleepers is left as it is. Nothing to do without bonds.
void BondForces(Workspace& m, Particles& p, const SleepConfig& sleep, double dt, double t_end,
                int nt);
// Makes Workspace::bond's live list, storage indices and per-particle entries again (clears
// bond.stale); m.index_of_id must name the present storage (as after a Rebuild).
void IndexBonds(Workspace& m, const Particles& p);

// --- dem/sleep.cpp: sleeping --------------------------------------------------------------------

// Sleep/wake decisions (every sleep.check_every steps); marks the lists stale when any changed.
void UpdateSleep(Workspace& m, Particles& p, const SleepConfig& sc, int nt);
// Lists the awake particles (Workspace::active), marks them moved since the build, and measures
// the sleepers' drift since the build.
void RefreshActive(Workspace& m, const Particles& p, int nt);
// Wakes every particle, with zero force and torque (sleeping switched off).
void WakeAll(Particles& p);

// --- dem/diagnostics.cpp: the step's health ----------------------------------------------------

// The status of a step that ended at `time`: finite (every v, w finite), max_v2 (largest |v|^2)
// and Workspace::max_overlap against the limits, with a diagnosis when one fails.
StepStatus CheckHealth(const Workspace& m, const Particles& p, const SystemConfig& config,
                       double time, bool finite, double max_v2);

}  // namespace dem::internal

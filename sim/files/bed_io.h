// Saved beds: the particle state and contact history of a settled bed in one HDF5 file, restored
// bit for bit, which also opens in ParaView through its XDMF3 sidecar.
//
// File layout (all arrays in persistent-id order, SI units):
//   /                  attributes version, scene_yaml (strings), time [s] (double),
//                      state_hash (16 hex digits) and state_hash_u64 (System::StateHash())
//   /snapshots/000000  the same particle snapshot as a run's output (see sim/files/h5_output.h)
//   /particles/        id int64 (N), position, velocity, angular_velocity (N x 3), radius (N),
//                      material int32 (N, index into /materials/names): hard links to the
//                      snapshot's datasets; force [N], torque [N m] (N x 3): the last step's,
//                      which velocity Verlet's first half kick uses (zero for a particle or
//                      clump that sleeps: it loads awake, at rest in equilibrium)
//   /materials/names   material names (string list, index = material id at save time)
//   /contacts/         a, b int64 (M), shear (M x 3) [m]: System::Contacts(); b < 0 is plane -1-b
//   Optional: /particles/awake uint8 (N): 0 for a particle that sleeps (dem::SleepConfig; it
//   is loaded at rest), else awake; SaveBed does not write it (a settled bed is all awake)
//   Only in a bed saved mid-pour: /pour_state uint8, the whole state (see SaveBed)
//   Only when the bed has clumps (dem/clump.h; a sphere bed's file has neither group):
//   /clump_templates/  names (T strings), sphere_count int32 (T), spheres (S_total x 4): x y z r
//                      of each template's spheres in its template frame [m], template after
//                      template
//   /clumps/           template, material int32 (C): indices into /clump_templates/names and
//                      /materials/names; position (C x 3): centre of mass [m]; orientation
//                      (C x 4): w x y z of the principal frame -> world; velocity, angular_velocity
//                      (world), angular_momentum (principal frame, restored exactly), force,
//                      torque (the last step's, about the CoM) (C x 3); member int64: the
//                      persistent ids of each clump's spheres (also in /particles), clump after
//                      clump, in template order
//   Only when the bed has bonds (issue 44, dem/bond.h; SaveBed writes them when the system has
//   any, intact or broken; LoadBed adds them as they are):
//   /bonds/            a, b int64 (B): persistent ids (a < b); intact uint8 (B): 1 intact, 0
//                      broken for good; radius [m], kn, ks [Pa/m], tensile_strength, cohesion
//                      [Pa] (+inf: never breaks), tan_friction, damping_ratio [-], fn [N]
//                      (tension positive), mt [N m] (B); fs [N], mb [N m], normal [-] (B x 3),
//                      world axes: dem::Bond's fields, in the system's bond order
//   <name>.xdmf        sidecar next to <name>.h5
#pragma once

#include <string>
#include <vector>

#include "dem/system.h"

namespace sim {

// Where a pour stands, kept up to date by FillAndSettle (a bed saved mid-pour carries it, and a
// pour resumed from that bed goes on from it).
struct PourPoint {
  int layers = 0;         // layers inserted so far
  int64_t poured = 0;     // bodies (spheres or clumps) inserted so far
  uint64_t rng = 0;       // dem::Rng state after the last insertion
  double layer_t0 = 0;    // time the last layer began to settle [s]
  double layer_fall = 0;  // its fall time, the least it settles [s]
  bool started = false;   // a layer has been inserted
  bool settled = false;   // the last layer has settled (the next is yet to be inserted)
};

// Writes `system` to `path` (parent folders created; written to a temporary file of this process
// and renamed, so an interrupted save never leaves a partial bed, nor do two processes saving at
// once). Throws sim::InputError if it cannot be created. With `pour`, the bed is an unfinished
// pour: root attributes pour_layers, pour_poured, pour_rng, pour_layer_t0, pour_layer_fall,
// pour_layer_settled (sim::PourPoint) say where it stopped, and /pour_state (uint8) holds the
// system's whole state (dem::System::SaveState), from which the pour goes on bit for bit.
void SaveBed(const std::string& path, const dem::System& system, const std::string& scene_yaml,
             const PourPoint* pour = nullptr);

// Whether `path` is a bed saved mid-pour of the scene text `scene_yaml`; if so *pour is where it
// stopped and, given `state`, *state its /pour_state (empty when the file has none). False for a
// missing or unreadable file, a finished bed or another scene's.
bool ReadPourPoint(const std::string& path, const std::string& scene_yaml, PourPoint* pour,
                   std::vector<char>* state = nullptr);

// Appends the saved particles to `system` (AddParticle in saved id order, so a bed loaded into an
// empty System keeps its ids), restores their last-step force and torque and their contact
// history (added to the system's existing history), and sets the system's time to the saved time.
// Materials are matched by name. Throws sim::InputError naming the file and the dataset on a
// missing file or dataset, a wrong shape or type, a non-finite value, a particle whose centre is
// outside the system's domain (the scene's box, whose top is open), or a material the system does
// not have.
void LoadBed(const std::string& path, dem::System* system);

// The scene text a bed file was made from (its root attribute `scene_yaml`); "" when the file
// cannot be opened or has no such attribute.
std::string BedSceneYaml(const std::string& path);

}  // namespace sim

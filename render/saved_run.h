// Frames from a saved run (`scoopsim render OUT.h5 --frames DIR`): every particle snapshot of a
// sim::H5Output file (layout in sim/files/h5_output.h) rendered in order. Public header.
#pragma once

#include <string>

#include "render/frames.h"

namespace render {

// Renders each /snapshots/NNNNNN of `h5_path` into `frames`, read through sim::SavedRun. The
// colour range is the whole run's (AutoRange over every snapshot, read once before the first
// frame) unless the options give one. The bed box comes from the scene stored in the file (root
// attribute scene_yaml), else from the particles' extent. The caption's time is the snapshot's, on
// the run's one clock (README "One clock"), and the caption takes pass, rho and |force_world| from
// /scoop/{time,pass,rho,force_world} when the file has them (the sample at or before the
// snapshot's time), else shows the time only. The meshes are those stored with the snapshot (the
// scoop, the arm's links, obstacles); for a file without them, the scoop is drawn from the mesh
// file named by the root attribute scoop_mesh at /scoop/pose (same sample), and a mesh that
// cannot be loaded any more is reported once and left out. With /arm/, the torque bars and fault
// flags are those of the last /arm/ sample at or before the snapshot (the first sample for
// a snapshot before it, the dig's first).
// Returns the number of frames written. Throws sim::InputError for a file that cannot be read as
// a run or for a field the snapshots lack (force: snapshots store no forces).
int RenderSavedRun(const std::string& h5_path, FrameSequence* frames, bool quiet);

}  // namespace render

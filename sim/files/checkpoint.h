// Run checkpoints (`scoopsim run --checkpoint-every S`, `--resume OUT.h5`): OUT.restart.h5 beside
// the output holds the whole mutable state of a run, and a run resumed from it writes the same
// output, bit for bit, as the run would have without the stop.
//
// File layout (HDF5, written to a temporary file and renamed):
//   /  attributes format = "scoopsim restart", format_version (kCheckpointFormat), version,
//      scene_path, scene_yaml (the scene text the run was made from), time [s]
//   /dem_state     uint8: dem::System::SaveState (particles, clumps, lists, contact and mesh
//                  history, sleeping, counters)
//   /world_state   uint8: the run loop's own state (sim::World: dig pass and its bookkeeping,
//                  row and snapshot cadence, summaries)
//   /output_state  uint8: the output's cursor (sim::OutputCursor: rows of each series,
//                  snapshots), as of the flush that went with the checkpoint
#pragma once

#include <string>
#include <vector>

#include "sim/files/h5_output.h"

namespace sim {

// 2 (2026-12-03): the workspace keeps the force pass's slab weights instead of its slab order.
// 3 (2026-12-06): the dig keeps the CoM's path length since first touch (/scoop/rho_path).
constexpr int kCheckpointFormat = 3;

struct Checkpoint {
  std::string scene_path, scene_yaml;
  double time = 0;  // [s]
  std::vector<char> dem_state, world_state, output_state;
};

// "OUT.restart.h5" beside OUT.h5.
std::string CheckpointPath(const std::string& output);

// Throws sim::InputError naming the path when it cannot be written.
void WriteCheckpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws sim::InputError (exit 2) naming the path for a missing or unreadable file, another
// format or another format version.
Checkpoint ReadCheckpoint(const std::string& path);

std::vector<char> EncodeCursor(const OutputCursor& cursor);
// Throws sim::InputError naming `path` when the bytes do not fit.
OutputCursor DecodeCursor(const std::vector<char>& bytes, const std::string& path);

}  // namespace sim

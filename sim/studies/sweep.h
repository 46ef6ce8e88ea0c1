// Sweeps: one base scene run many times with some of its keys varied, each case an independent
// run, farmed out plainly (one after another), over Open MPI (`mpirun -np N`: cases handed out
// dynamically, longest first) or by a batch scheduler's job array (`--case I`), and resumed
// after a stop: finished cases are skipped and a stopped case goes on from its last checkpoint
// (its pour so far, or its running pass), else from its last finished pass.
//
// The sweep file (YAML; paths relative to it):
//   scene: ../tiny_dig.yaml              the base scene (required)
//   grid:                                every combination; the first key varies slowest
//     bed.material: [snow, ice]          a scene key path: a list of values ...
//     dig.bite_depth: {b10: 0.01, b20: 0.02}   ... or a map label: value
//     scene: {snow: a.yaml, ice: b.yaml} the key `scene` swaps the base scene itself
//   cases:                               single cases, after the grid's (either or both)
//     - {name: deep, set: {dig.bite_depth: 0.03, dig.passes: 3}}   name optional
//   notes: free text                     optional
// A key path is a dotted path into the scene's maps ("dig.trajectory.linear.speed"; "[i]"
// indexes a list: "dig.trajectory.moves[2].rate"); a value may be any YAML (a map replaces the
// whole subtree, as in `bed: {...}`), and null (~) removes the key. A case's name is its values'
// labels joined by '_' (a map entry's label, else the value's text), unless given.
//
// A case is the base scene with its settings as the command line's overrides (`--set KEY=VALUE`,
// sim/input/yaml_input.h: "[i]" written ".i"): its text is the base file's, a comment naming the
// case, then a `# scoopsim --set KEY=VALUE` line per setting, loaded with the normal scene loader
// (sim::LoadSceneText), so every case is validated whole at load, and that text is the scene
// text stored in its output. Errors name the sweep file, the line of the value, the key and what
// was expected (sim::InputError; the CLI exits 2). A scene with `arm:` (the base, or a case's) is
// refused: a sweep digs kinematically (sim::RefuseArmScene).
//
// The output folder DIR:
//   DIR/cases/<name>.h5        the case's run output, as `scoopsim run` writes it
//   (sim/files/h5_output.h)
//                              plus root attributes sweep_case, sweep_index and /sweep/pass_wall_s,
//                              /sweep/pass_cpu_s (one row per pass, wall and CPU seconds),
//                              root attributes sweep_cpu_s (the passes' CPU seconds, all
//                              threads) and sweep_bed_cpu_s (the pour's, 0 for a saved bed),
//                              and the table cell it fills, from its validated scene
//                              (table_material, table_bite_depth, table_particle_size:
//                              sim::WriteTableCell); written when the case's last pass is done
//   DIR/cases/<name>.status    its status record (text, "key: value" lines; written to a
//                              temporary file and renamed): state (running, done, failed,
//                              stopped), passes, passes_done, surface, clear_z, scene_hash, ...
//   DIR/cases/<name>.parts/    while it runs: bed_<k>.h5, the bed after pass k (bed_0.h5 the
//                              settled bed when the scene makes its own) and pass_<k>.h5, the rows
//                              of pass k; removed when the case is done;
//                              also, every --checkpoint-every seconds of wall time
//                              (SweepOptions::checkpoint_every) and when stopped by a signal,
//                              pour.h5 (the pour so far: a saved bed with the whole state,
//                              sim/files/bed_io.h) and pass_<k>.restart.h5 (the running pass's
//                              checkpoint, sim/files/checkpoint.h), from which a resumed case goes
//                              on bit for bit
//   DIR/cases/<name>.lock      flock'ed while a process runs the case (two never run one case)
//   DIR/table.h5               the wrench table (sim/files/wrench_table.h), built when every case
//   is done
// Test hook: SCOOPSIM_SWEEP_KILL=<case>:<pass>:<seconds> SIGKILLs the process that many simulated
// seconds into that pass of that case (pass 0: the pour, just after a keep); with :TERM appended
// it raises SIGTERM instead, just after a keep (pour or pass; a pass keeps only with
// --checkpoint-every): the case is then kept, its status `stopped`, its line "stopped ...
// kept", and the sweep exits 130.
//
// Each pass runs in a fresh World from the bed the previous pass left (saved, then loaded), in
// an uninterrupted run as in a resumed one, so a resumed case's rows equal the uninterrupted
// ones bit for bit (a saved bed keeps positions, velocities, forces and contact history, not
// sleep states or neighbour lists, which therefore restart at every pass in both). A case's
// output does not depend on the rank that ran it, the rank count or its thread count.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "sim/input/scene.h"

namespace sim {

struct SweepSetting {
  std::string key;    // scene key path ("dig.bite_depth"), or "scene"
  std::string value;  // the value as YAML text (for logs)
  int line = 0;       // of the value in the sweep file (1-based)
};

struct SweepCase {
  int index = 0;     // 0-based, in the sweep's order (`--case I`)
  std::string name;  // [A-Za-z0-9._-]+, unique in the sweep
  std::vector<SweepSetting> settings;
  Scene scene;          // validated; yaml_text is the base scene's with the settings as --set
  double estimate = 0;  // cost: particles x planned simulated time / time step [-]
};

struct Sweep {
  std::string path;
  std::vector<SweepCase> cases;
};

// Loads and validates a sweep file and every case's scene. Throws InputError (file, line, key,
// expectation): unknown scene key path, empty grid or value list, duplicate or malformed names.
Sweep LoadSweep(const std::string& path);

// The cases as `scoopsim sweep --list` prints them: a line each, tab-separated: index, name,
// settings ("key = value, ..."), estimated cost and, with an output folder `dir`, where the case
// stands there (CaseState).
std::string SweepCaseList(const Sweep& sweep, const std::string& dir = "");

// Where a case stands in the output folder `dir`, from its status record and lock, in words:
// "not started"; "done"; "running (another process holds DIR/cases/NAME.lock): the pour" or
// ": pass k of n"; "stopped: ..." (by a signal, kept: the same command goes on); "killed: ..."
// (the record says running but no process holds the lock: the same command goes on from the last
// keep); "failed (exit E): message"; "made from another scene text" when its record's hash is not
// the case's. Running, stopped and killed add the CPU seconds of the pour or of the running pass
// up to its last keep.
std::string CaseState(const SweepCase& c, const std::string& dir);

struct SweepOptions {
  std::string dir = "out/sweep";
  int threads = -1;         // per case; -1: the scene's `threads` (plain) or 1 (a rank of MPI)
  bool quiet = false;       // no progress line of each run (the per-case lines stay)
  int only_case = -1;       // >= 0: run this case alone (no MPI, no table)
  bool build_table = true;  // DIR/table.h5 once every case is done
  // Wall-time period [s] of a case's pour keeps and pass checkpoints (0: none; a stopped case
  // then goes on from its last finished pass, its pour made again).
  double checkpoint_every = 600;
  // Called once every case is done, where the table is built (the plain runner, or rank 0 under
  // MPI before MPI_Finalize; not with only_case), after the table. A study on a sweep's cases
  // (`study particle-size`) sets a flag here and reads the cases once RunSweep has returned.
  std::function<void()> on_complete;
};

// `scoopsim sweep SWEEP.yaml -o DIR`: runs (or resumes) the sweep's cases. Under mpirun (Open
// MPI's OMPI_COMM_WORLD_SIZE or a PMI environment set) with more than one rank, MPI is started
// and rank 0 hands the cases out (it also runs cases itself, on a second thread, so N ranks run
// N cases at once); otherwise they run one after another. Returns the exit status: 0 when every
// case is done, else that of the first case that failed (130 when stopped by a signal).
int RunSweep(const Sweep& sweep, const SweepOptions& options);

// The status record of a case (DIR/cases/<name>.status).
struct CaseStatus {
  std::string state;       // "" (none), running, done, failed, stopped
  int index = -1;          // the case's index
  int passes = 0;          // planned
  int passes_done = 0;     // finished and saved
  double surface = 0;      // original surface of the dig [m] (after pass 1)
  double clear_z = 0;      // clearance height of the dig [m] (after pass 1)
  std::string scene_hash;  // FNV-1a 64 of the case's scene text, 16 hex digits
  int exit_status = 0;     // of the last attempt
  double wall_s = 0;       // wall time of the case so far, all attempts [s]
  double bed_cpu_s = 0;    // CPU time of pouring its bed, all threads [s] (0: a saved bed)
                           // (while it pours: up to its last keep)
  double pass_wall_s = 0;  // the running pass's wall time up to its last checkpoint [s]
  double pass_cpu_s = 0;   // and its CPU time [s]
  std::string message;     // what went wrong, if anything
};
// Reads a record; state "" when there is none. Throws InputError for a malformed one.
CaseStatus ReadCaseStatus(const std::string& path);
// Writes a record atomically (a temporary file renamed over it).
void WriteCaseStatus(const std::string& path, const CaseStatus& status);
// FNV-1a 64 of a text, as 16 hex digits.
std::string TextHash(const std::string& text);

}  // namespace sim

// The commands behind the CLI: make a bed, run a scene, the shape study, benchmarks. Each is a
// few lines around sim::World (sim/loop/world.h), the one run loop, and returns a process exit
// status (sim/input/exit_status.h); bad input throws sim::InputError (the CLI prints it and exits
// 2).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/files/world_view.h"
#include "sim/input/scene.h"
#include "sim/loop/world.h"
#include "sim/studies/balovnev.h"

namespace sim {

// Where a command that pours keeps the bed poured so far (World::KeepPour): OUT.h5 -> OUT.pour.h5.
std::string PourPath(const std::string& output);
// Creates the parent folders of `path` and checks a file can be created there and an output can
// go there (sim::CheckOutputPath); throws sim::InputError naming the path and the reason.
void CheckWritable(const std::string& path);

// Throws sim::InputError when `output` is the file `input` (the same file by any path; "" never
// is): a run must not overwrite its own input. `what` names the input ("scenes/x.yaml: bed.file").
void RefuseOutputOverInput(const std::string& output, const std::string& input,
                           const std::string& what);
// The same for every file a scene reads: the scene, its materials file, the scoop mesh, the
// arm's URDF and (with `bed_file`) bed.file.
void RefuseOutputOverScene(const std::string& output, const Scene& scene, bool bed_file = true);

// The Python that runs the tools' scripts: the environment's SCOOPSIM_PYTHON when set and not
// empty, else `python3` as PATH finds it (any Python with numpy, h5py and matplotlib: a venv's, or
// Debian's /usr/bin/python3 with the packages of tools/install-deps.sh).
std::string PythonInterpreter();
// The folder of the tools' scripts: PREFIX/share/scoopsim/tools beside an installed
// PREFIX/bin/scoopsim, else the source tree's tools/.
std::string ToolsDir();
// Runs PythonInterpreter() ToolsDir()/<script> with `args` (each quoted for the shell), as the
// studies draw their figures; false (and a line on stderr naming the command) when it fails.
bool RunPlotScript(const std::string& script, const std::vector<std::string>& args);
// The same, returning 0 (done), 2 (the script refused its input: its one line is on stderr) or 1
// (it failed otherwise, or Python could not run it: a line saying so).
int RunToolScript(const std::string& script, const std::vector<std::string>& args);

// `scoopsim bed SCENE -o BED.h5`: fill the scene's box, settle, save the bed.
int MakeBed(const Scene& scene, const RunOptions& options);

// `scoopsim run SCENE -o OUT.h5`: load (or make) the bed and run for scene.duration. With
// checkpoint_every, the run's state is kept in CheckpointPath(OUT.h5) that often (and when
// stopped by a signal), removed when the run ends; with resume, the run goes on from it (its
// scene text must be the scene's) and writes the same output as the uninterrupted run. A scene
// with an arm cannot be checkpointed (Bullet's solver state is not saved): InputError.
int RunScene(const Scene& scene, const RunOptions& options);

// `scoopsim study shape SCENE -o OUT.h5`: the shape-complexity study (paper section 4, Fig. 8,
// Table 3). The scene's dig is run once per clump template, each on its own bed of that template
// (sim::WithClumpBed: the same solid volume as the scene's bed, the template's time step), and
// one HDF5 file holds them all:
//   /                 attributes scene_yaml, version, study = "shape", templates (comma list)
//   /<template>/scoop/, /<template>/series/   that dig's rows, as a run's /scoop/ and /series/
//   /<template>       attributes spheres_per_clump, clumps, spheres, time_step [s], bed_wall_s,
//                     dig_wall_s (wall-clock), dig_cpu_s (all threads), steps, peak_force,
//                     mean_force [N] (|F| in the world
//                     frame; the mean after first contact), peak_torque [N m], peak_overlap
//                     (deepest overlap / smaller diameter over the dig's steps), state_hash, and
//                     the dig's own (surface, scoop_mesh, ...)
//   /table/           one row per template, in order: spheres_per_clump, clumps, spheres,
//                     time_step, bed_wall_s, dig_wall_s, dig_cpu_s, peak_force, mean_force,
//                     peak_overlap (n)
// The table is also printed on stderr. Beds are made (and settled) per template; with bed_dir,
// DIR/<template>.h5 is loaded when it exists, else made and saved there.
struct ShapeStudyOptions {
  int threads = 0;  // 0 = all cores
  std::string output;
  bool quiet = false;
  std::vector<std::string> templates;  // built-in or scene template names; empty = the four
                                       // tetrahedra of the study (tetra1, tetra4, tetra8, tetra12)
  std::string bed_dir;
};
int RunShapeStudy(const Scene& scene, const ShapeStudyOptions& options);

// `scoopsim study balovnev SCENE -o OUT.h5`: the scene's dig (pass 1, as `scoopsim run` makes
// it, into OUT.h5) against Balovnev's model (sim/studies/balovnev.h) along the same path. Between
// the bed and the dig the bed's surface is measured as a height field (sim::SurfaceMap: columns of
// one particle diameter, the mean of the 3 x 3 around a point) and its solid fraction (the central
// part, 4 radii from the side walls, up to two diameters under the mean surface); gamma =
// solid fraction x particle density x |g|. At each /scoop/ row the cutting depth is the blade
// tip's depth below that surface (0 above it); the DEM's horizontal force is -F_world . trench
// (against the motion) and its vertical -F_world.z (downward, Balovnev's F_v's sense). Writes
// OUT.balovnev.csv (one row per /scoop/ row: time since the dig began, pass, rho, tip_x, tip_y,
// tip_z, surface, depth, dem_horizontal, dem_down, balovnev_horizontal, balovnev_vertical (the
// textbook model: A split at x*), plugin_horizontal, plugin_vertical (the same with the plugin's
// A_II), lander_horizontal, lander_vertical (the lander plugin's variant, BalovnevLander: its own
// rho_bulk, g, q, b = 0 and caps); '#' lines state the parameters), prints a table (ten spans of
// the rows that cut, and their mean) of the models `show_textbook` / `show_lander` choose on
// stdout, and with `plot` draws them in OUT.balovnev.png by tools/plot_balovnev.py
// (PythonInterpreter(); exit 1 if that fails).
struct BalovnevStudyOptions {
  int threads = 0;  // 0 = all cores
  std::string output;
  bool quiet = false;
  bool plot = true;
  BalovnevTool tool;    // FACTS.md section 7's scoop
  BalovnevSoil soil;    // phi, delta, c, q; unit_weight is measured on the bed
  bool buried = false;  // b
  bool show_textbook = true, show_lander = true;  // the models the table and plot show
};
int RunBalovnevStudy(const Scene& scene, const BalovnevStudyOptions& options);
std::string BalovnevCsvPath(const std::string& output);  // OUT.h5 -> OUT.balovnev.csv
std::string BalovnevPngPath(const std::string& output);  // OUT.h5 -> OUT.balovnev.png

// `scoopsim study particle-size SCENE -o DIR`: the particle-size study (paper section 4, eq. 5-7,
// Fig. 3-6; definitions in sim/studies/size_study.h). The scene (spheres of one diameter d0,
// poured, one pass of a dig) is run once per diameter d and bed: bed.radius d/2, bed.count x
// (d0/d)^3 (the same solid volume), neighbor.skin x d/d0, bed.seed + bed - 1. The cases are a sweep
// (sim/studies/sweep.h), written to DIR/size_study.sweep.yaml and run as `scoopsim sweep` runs one:
// into DIR/cases/<name>.h5 (names d<mm>_b<bed>), finished cases skipped, a stopped case resumed,
// under `mpirun -np N` handed out to the ranks, one case alone with only_case. Once every case is
// done (where the sweep would build its table: the plain runner or rank 0), each case's |F| and |T|
// after first contact are smoothed and their peaks compared with the finest size's (eq. 6-7):
//   DIR/size_study.csv   '#' lines (scene, smoothing rule, reference size, eq. 6 and 7 rules,
//                        `# verdict: largest_within_20pct_mm=<d>` and the same with the spread),
//                        then one row per size: size_mm, beds, peak_force_mean/min/max,
//                        mpe_force_pct/min_pct/max_pct, peak_torque_mean/min/max,
//                        mpe_torque_pct/min_pct/max_pct, within_20 (1/0), cpu_s_mean (pour + dig,
//                        all threads, mean over beds)
//   DIR/size_curves.csv  every case's curve: size_mm, bed, time (since first contact), rho, force,
//                        torque, force_smooth, torque_smooth
//   stdout               the table
//   DIR/size_force.png, DIR/size_stack.png, DIR/size_mpe.png   by tools/plot_size_study.py
//                        (Fig. 3, 4 and 6 analogues; PythonInterpreter(); exit 1 if it fails)
struct SizeStudyOptions {
  std::string dir = "out/size_study";
  std::vector<double> sizes_mm;  // empty: the study's S (eq. 5)
  int beds = 3;                  // independent beds per size
  int threads = -1;              // per case; -1: the scene's `threads` (plain) or 1 (MPI rank)
  bool quiet = false;            // no progress line within a case
  bool list = false;             // print the cases (index, name, settings, cost) and stop
  int only_case = -1;            // >= 0: run this case alone (no analysis)
  double smooth_s = 0.05;        // the moving mean's window [s]
  bool plot = true;
  // Earlier runs' DIR/size_study.csv files (`--prior`): their rows (peaks, beds, cost) join this
  // run's in eq. 6-7, so a study too long for one sitting is run size by size. A size run here
  // is taken from here; otherwise from the first file that has it.
  std::vector<std::string> priors;
  double checkpoint_every = 600;  // [s] of wall time; sim::SweepOptions::checkpoint_every
};
int RunSizeStudy(const std::string& scene_path, const SizeStudyOptions& options);

struct BenchSettleOptions {
  int64_t particles = 50000;
  int64_t steps = 2000;
  int threads = 0;
  std::string cache_dir;  // where the settled bed is cached; "" = <source>/bench/cache
};
// `scoopsim bench settle`: prints one JSON line (particles, steps, threads, wall_s,
// particle_steps_per_s, contacts_per_particle, peak_rss_mb, state_hash).
int BenchSettle(const BenchSettleOptions& options);

struct BenchStepOptions {
  std::string scene;   // a scene with a bed file (its sleep state, when saved, is restored)
  // Or a run's checkpoint (OUT.restart.h5): the dig goes on from it, under the scene it holds
  // (a real mid-dig state: the scoop in the bed, its contacts' history, the sleepers asleep).
  std::string checkpoint;
  // --set KEY=VALUE lines on the scene (the checkpoint's too: its lists are then made again from
  // the changed scene before the first step, e.g. another neighbor.skin on the same state).
  std::vector<std::string> sets;
  int64_t warm = 400;  // steps run before the timing (sleep checks settle, a rebuild or two)
  int64_t steps = 1500;
  int threads = 0;
  // A URDF: its arm (the ArmDriver of a coupled dig, the lander's PID with its D term implicit,
  // holding the scoop buried at the box's centre under a constant 20 N) steps once per DEM step,
  // as a coupled dig's arm does at arm.substeps 1; its time is taken apart (arm_ms_per_step).
  std::string arm;
};
// `scoopsim bench step SCENE`: the cost of the scene's step from its saved bed, scoop or not (the
// mid-dig state of bench/dig_state.py: a full-scale pass's step without running up to it). Prints
// one JSON line (particles, awake_per_step, steps, threads, wall_s, ms_per_step,
// awake_particle_steps_per_s, neighbor_builds, near_builds, peak_rss_mb, state_hash; with --arm
// also arm_ms_per_step, included in ms_per_step).
int BenchStep(const BenchStepOptions& options);

}  // namespace sim

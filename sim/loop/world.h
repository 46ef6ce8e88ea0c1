// The run loop: one World owns the DEM system, the scoop and its driver, and the outputs, and
// advances them together one step at a time. Every command goes through it: `scoopsim bed`
// (Pour), `scoopsim run` with and without a dig (the arm's on a wrench table too), the sweeps and
// studies and `bench step`.
//
//   World world(scene, threads);
//   world.LoadBed(path) or world.Pour(...)           the bed (none for a driver with its own
//                                                    wrench: ScoopDriver::OwnStep() > 0)
//   world.OpenOutput(path) / UseOutput(&out)         optional: HDF5 rows, snapshots
//   world.StartDig(MakeScoopDriver(scene))           optional: the scoop and its driver
//   RunResult r = world.Run(control);                steps until the end, a signal or a fault
//
// Step() is the loop's body, usable on its own: it never throws and reports the step's health.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dem/system.h"
#include "sim/files/checkpoint.h"
#include "sim/files/h5_output.h"
#include "sim/files/world_view.h"
#include "sim/input/scene.h"
#include "sim/loop/bed.h"
#include "sim/loop/dig.h"
#include "sim/loop/scoop_driver.h"

namespace sim {

// What a dig measured, for callers that want numbers rather than the HDF5 file (tests,
// studies). Magnitudes of the wrench in the world frame about the scoop CoM, over all rows.
struct DigSummary {
  double peak_force = 0;               // max |F| [N]
  double mean_force = 0;               // mean |F| over the rows after first contact [N]
  double peak_torque = 0;              // max |T| [N m]
  double peak_overlap = 0;             // deepest overlap / smaller diameter over all steps [-]
  std::vector<double> collected_mass;  // per pass [kg]
  int64_t particles = 0;               // at the start of the dig
  int64_t steps = 0;
  double simulated = 0;  // [s]
};

// The run loop's own bit of the health mask World::Step() returns (dem's flags use the low bits,
// dem/system.h): an output could not be written (disk full, file removed); the message says
// which file and why. Run() stops with exit status 1.
constexpr uint32_t kOutputFailed = 1u << 16;

// How Run() is watched and stopped.
struct RunControl {
  bool quiet = false;      // no progress line
  double stop_after = 0;   // stop after this much simulated time [s] (0: run to the end)
  FrameCallback on_frame;  // frames at the start and then every frame_every seconds
  double frame_every = 0;  // [s]; 0 = output.interval (plain run), 0.05 s (dig)
  // Called by the loop thread when dig pass `pass` has ended and its sample has been taken out,
  // before the next pass begins (a sweep saves the bed there, to resume from). Return false to
  // stop the run at that point (RunResult::stopped_at_pass). It may throw: the run then stops as
  // for an output failure (exit status 1, the message printed).
  std::function<bool(int pass)> on_pass_end;
  // At the start and every checkpoint_every seconds of wall time (0: never), between steps, the
  // output is flushed and the run's whole state written to checkpoint_path
  // (sim/files/checkpoint.h); on_checkpoint (optional) is called after each one is written.
  double checkpoint_every = 0;  // [s]
  std::string checkpoint_path;
  std::function<void()> on_checkpoint;
  // With checkpoint_every, stop_after also writes one where it stops (as a signal does), so that
  // the run goes on from there (`run --stop-after T --checkpoint-every S`: a mid-dig state at T).
  // A sweep's simulated kill leaves it false: a killed run keeps only its last periodic one.
  bool checkpoint_at_stop_after = false;
};

// Where a dig starts when it does not start at its first pass: a dig resumed from the bed that
// pass first_pass - 1 left (a sweep's case restarted after a stop). The original surface and
// the clearance height are those the first pass measured (World::ResumePoint()), so every pass
// cuts where it would have in one uninterrupted run.
struct DigResume {
  int first_pass = 1;  // 1-based
  double surface = 0;  // world z of the original free surface [m]
  double clear_z = 0;  // world z the scoop is lowered from (BedContext::clear_z) [m]
};

struct RunResult {
  int exit_status = 0;         // sim::ExitStatus
  bool stopped_after = false;  // RunControl::stop_after ended it
  int stopped_at_pass = 0;     // RunControl::on_pass_end returned false after this pass
  double wall = 0;             // [s]
};

class World {
 public:
  // A world of `scene`'s model (materials, walls, step) and no particles yet. threads 0 = all.
  World(const Scene& scene, int threads);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // The bed: a saved one (storage canonicalised), or poured and settled now with a progress line
  // (returns kExitOk, kExitNotSettled with the bed kept, kExitUnstable or kExitStopped).
  // A bed made with bed.bonds gets its bonds here (BondBed) when the file holds none.
  void LoadBed(const std::string& path);
  // Makes the scene's bonds (bed.bonds, sim::MakeBedBonds at sim::BondSurface) in a bed that has
  // none, and prints one line (how many, the mean per sphere); returns how many it made. A bed
  // that has bonds (a saved bonded bed, a checkpoint) keeps them as they are; a scene without
  // bed.bonds makes none. RunScene calls it after a pour.
  int64_t BondBed();
  // A saved mid-run state (bench step): loaded, the scene's sleep settings applied to its sleep
  // flags, then the storage made canonical, so a plain run continues it with no further rebuild.
  void LoadState(const std::string& path);
  int Pour(bool quiet, SettleReport* report);
  // Pour() keeps the bed poured so far in `path` (a saved bed with its sim::PourPoint and the
  // whole state) every `every` seconds of wall time (0: output.flush_seconds), but never more
  // often than ten times the last keep's own wall time, and when stopped by a signal; goes on
  // from it, bit for bit, when it holds an unfinished pour of this scene; and removes it once the
  // pour has ended. `on_keep` is called after each keep is written.
  void KeepPour(const std::string& path, double every = 0, std::function<void()> on_keep = {});

  // Outputs: a file of its own (created now; with `resume`, made again up to that cursor from
  // the file at `path`, see H5Output), or a shared one (a study's groups).
  void OpenOutput(const std::string& path, const OutputCursor* resume = nullptr);
  void UseOutput(H5Output* out);
  H5Output* output() { return out_; }

  // Adds the scene's scoop mesh and starts its first pass under `driver` (or pass
  // resume->first_pass, with the original surface and clearance given). Without it, Step()
  // advances the particles alone (scene.sleep applies either way).
  void StartDig(std::unique_ptr<ScoopDriver> driver, const DigResume* resume = nullptr);
  // The pass the dig is at (the next one, between passes) and the surface and clearance of its
  // first pass: what StartDig needs to resume from a bed saved now. Only during a dig.
  DigResume ResumePoint() const;

  // The run's whole state between two steps (the output flushed first), and a world set up as
  // this one was (same scene, output opened with the checkpoint's cursor, nothing else done)
  // made to go on from it: with `driver` (a dig), StartDig(driver) at the checkpoint's pass,
  // then the DEM state and the loop's own. Run() then writes what the uninterrupted run would
  // have, bit for bit. ResumeFrom throws sim::InputError naming `source` when the state does not
  // fit this world.
  Checkpoint MakeCheckpoint();
  void ResumeFrom(const Checkpoint& checkpoint, std::unique_ptr<ScoopDriver> driver,
                  const std::string& source);

  // One step: the driver's motion for the end of the step, the DEM step, the wrench back to the
  // driver, output rows; at a pass's end the sample is taken out and the next pass begins. After
  // a dig's last pass it does nothing; a plain run steps past the scene's duration (bench step).
  // Never throws; reports the step's health, dem's flags and kOutputFailed (the caller decides
  // to stop).
  dem::StepStatus Step() noexcept;
  // All passes done (a dig), or the scene's duration reached (a plain run).
  bool Done() const;
  // Steps until Done(), a fault, a signal or control.stop_after, with the progress line,
  // periodic flushes and frames; ends with the summary lines and the output's final attributes.
  RunResult Run(const RunControl& control);

  // Simulated time the whole run is planned to take from the start [s].
  double PlannedDuration() const;
  // The loop's step [s]: the DEM's, or the driver's when it brings its own wrench (no bed).
  double StepSize() const;
  const dem::System& system() const { return *system_; }
  dem::System& mutable_system() { return *system_; }
  const DigSummary& dig_summary() const { return summary_; }
  // The scoop's wrench of the last step about its CoM in the world, l_scoop and body frames
  // (what the /scoop/ rows hold); nullptr without a dig.
  const ScoopWrench* scoop_wrench() const;
  // The scoop's mesh in system() (its pose and twist: system().mesh_motion(k)); -1 without a dig.
  int scoop_mesh() const;
  // Begins a plain run (no dig) as Run() does, for a caller that calls Step() itself (the Python
  // module); does nothing once a dig or a plain run has begun.
  void StartPlainRun() {
    if (!dig_ && !started_) StartPlain();
  }
  const Scene& scene() const { return scene_; }

 private:
  struct Dig;
  void StartPlain();
  void PlanSnapshots();       // tells the output how many snapshots the planned run makes
  int64_t StepsDone() const;  // loop steps since the run (plain or dig) began
  void Record();              // the rows, snapshots and pass changes that follow a step (may throw)
  void RecordPlainRow();
  void RecordDigRow();
  void RecordBondRow();     // /bonds/time and /bonds/intact (a bonded bed, beside /series/ rows)
  void RecordBondBreaks();  // the step's broken bonds to /bonds/broken/ (taken every step)
  void BeginPass();
  void EndPass();
  void AddObstacles();  // scene.obstacles as fixed meshes (at StartDig)
  WorldView View() const;
  // Lists the loop's own state: counters, summaries and, in a dig, its pass bookkeeping.
  template <typename Archive>
  void LoopFields(Archive& archive);

  Scene scene_;
  std::unique_ptr<dem::System> system_;
  std::unique_ptr<H5Output> owned_out_;
  H5Output* out_ = nullptr;
  std::unique_ptr<Dig> dig_;
  DigSummary summary_;
  bool started_ = false;        // a dig or a plain run has begun
  bool sleep_applied_ = false;  // the scene's sleep settings are in force (LoadState)
  double t_start_ = 0;          // time at which it began (after the bed) [s]
  double next_row_ = 0;
  int64_t step0_ = 0;
  int64_t particle_steps_ = 0;           // of the awake particles (all of them without sleeping)
  std::vector<int> obstacle_meshes_;     // mesh indices of scene.obstacles
  const RunControl* control_ = nullptr;  // during Run(): its on_pass_end
  int halted_after_pass_ = 0;            // on_pass_end returned false after this pass
  std::string pour_file_;                // KeepPour
  double pour_every_ = 0;                // [s]
  std::function<void()> on_keep_;
};

// How a command runs a scene (sim::RunScene, sim::MakeBed).
struct RunOptions {
  int threads = 0;     // 0 = all cores
  std::string output;  // output HDF5 path
  bool quiet = false;  // no progress output
  // Frames: when set, RunScene calls on_frame at t0 and then every frame_every simulated seconds
  // (0 = at every output interval), from the main thread, with no OpenMP region active.
  FrameCallback on_frame;
  double frame_every = 0;             // [s]
  double stop_after = 0;              // stop after this much simulated time [s] (0: run to the end)
  DigSummary* dig_summary = nullptr;  // filled by a dig run when set
  double checkpoint_every = 0;        // keep OUT.restart.h5 every this many wall seconds (0: no)
  bool resume = false;                // go on from OUT.restart.h5 (sim/files/checkpoint.h)
  // Each step's worker count picked by timing (dem::ThreadGovernor), up to `threads`; false:
  // exactly `threads` every step. Results are the same either way.
  bool adaptive_threads = false;
};

}  // namespace sim

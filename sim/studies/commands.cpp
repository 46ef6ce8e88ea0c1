#include "sim/studies/commands.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>

#include "arm/arm_model.h"
#include "sim/files/bed_io.h"
#include "sim/files/checkpoint.h"
#include "sim/files/h5_output.h"
#include "sim/files/internal_h5.h"
#include "sim/input/exit_status.h"
#include "sim/input/yaml_input.h"
#include "sim/loop/arm_driver.h"
#include "sim/loop/bed.h"
#include "sim/loop/preflight.h"
#include "sim/loop/progress.h"
#include "sim/loop/world.h"

namespace sim {
namespace {

RunControl Control(const RunOptions& options) {
  RunControl control;
  control.quiet = options.quiet;
  control.stop_after = options.stop_after;
  control.on_frame = options.on_frame;
  control.frame_every = options.frame_every;
  return control;
}

// CPU time of the process so far, all threads [s].
double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double PeakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace

std::string PourPath(const std::string& output) {
  return std::filesystem::path(output).replace_extension(".pour.h5").string();
}

void CheckWritable(const std::string& path) {
  h5::MakeParentFolders(path);
  CheckOutputPath(path);
  // A file of our own beside it, created and removed: the folder takes new files.
  const std::string probe = path + "." + std::to_string(::getpid()) + ".probe";
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (f == nullptr) {
    throw InputError(path + ": cannot write there: " + std::strerror(errno));
  }
  std::fclose(f);
  std::error_code ignored;
  std::filesystem::remove(probe, ignored);
}

std::string PythonInterpreter() {
  const char* chosen = std::getenv("SCOOPSIM_PYTHON");
  return chosen != nullptr && chosen[0] != '\0' ? chosen : "python3";
}

std::string ToolsDir() {
  namespace fs = std::filesystem;
  // An installed binary (PREFIX/bin/scoopsim) has its scripts in PREFIX/share/scoopsim/tools
  // (cmake/install.cmake); the build tree's binary, and a program of a user's that links sim,
  // those of the source tree.
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path() / SCOOPSIM_BIN_TO_DATA / "tools";
    if (fs::is_directory(installed, ec)) return installed.lexically_normal().string();
  }
  return std::string(SCOOPSIM_SOURCE_DIR) + "/tools";
}

bool RunPlotScript(const std::string& script, const std::vector<std::string>& args) {
  return RunToolScript(script, args) == 0;
}

int RunToolScript(const std::string& script, const std::vector<std::string>& args) {
  const auto quote = [](const std::string& text) {
    std::string q = "'";
    for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::string command = quote(PythonInterpreter()) + " " + quote(ToolsDir() + "/" + script);
  for (const std::string& arg : args) command += " " + quote(arg);
  const int status = std::system(command.c_str());
  if (status == 0) return 0;
  // The script's own exit status (2: it refused its input, with its one line on stderr).
  const int code = status > 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 2) return 2;
  std::fprintf(stderr,
               "scoopsim: the script failed: %s (the Python of SCOOPSIM_PYTHON, else python3 on "
               "PATH, needs numpy, h5py and matplotlib)\n",
               command.c_str());
  return 1;
}

void RefuseOutputOverInput(const std::string& output, const std::string& input,
                           const std::string& what) {
  namespace fs = std::filesystem;
  if (input.empty()) return;
  std::error_code ec;
  const bool same = fs::exists(output, ec) && fs::exists(input, ec)
                        ? fs::equivalent(output, input, ec)
                        : fs::weakly_canonical(output, ec) == fs::weakly_canonical(input, ec);
  if (same) {
    throw InputError(output + ": -o names the run's own input (" + what + " = " + input +
                     "); give another output file");
  }
}

void RefuseOutputOverScene(const std::string& output, const Scene& scene, bool bed_file) {
  RefuseOutputOverInput(output, scene.path, "the scene");
  RefuseOutputOverInput(output, scene.materials_path, scene.path + ": materials");
  if (scene.dig.enabled)
    RefuseOutputOverInput(output, scene.dig.scoop.mesh, scene.path + ": dig.scoop.mesh");
  if (scene.arm.enabled) RefuseOutputOverInput(output, scene.arm.urdf, scene.path + ": arm.urdf");
  if (bed_file) RefuseOutputOverInput(output, scene.bed.file, scene.path + ": bed.file");
}

int MakeBed(const Scene& scene, const RunOptions& options) {
  InstallStopHandlers();
  // (`bed` may write the scene's own bed.file: the scene that loads the bed it makes.)
  RefuseOutputOverScene(options.output, scene, /*bed_file=*/false);
  // The output's folder is made and checked for writing before any work.
  CheckWritable(options.output);
  World world(scene, options.threads);
  world.mutable_system().set_adaptive_threads(options.adaptive_threads);
  world.KeepPour(PourPath(options.output));
  const auto wall0 = std::chrono::steady_clock::now();
  SettleReport r;
  const int status = world.Pour(options.quiet, &r);
  if (status != kExitOk && status != kExitNotSettled) return status;
  SaveBed(options.output, world.system(), scene.yaml_text);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  Status(
      "scoopsim: bed of %lld particles (%zu spheres), %d layer(s), %.3f s simulated in %.1f s; "
      "saved %s\n",
      static_cast<long long>(world.system().num_bodies()), world.system().particles().size(),
      r.layers, r.sim_time, wall, options.output.c_str());
  return status;
}

namespace {

// Whether `scene` is the checkpoint's scene but for more dig passes: its document (the --set lines
// applied) equals the stored one's once dig.passes is set alike, and it asks for as many passes
// or more (so a resume given the same --set dig.passes=N again is the same scene). Pass
// k of a dig does not depend on how many follow it (World::Step begins the next pass when one
// ends), so a run of fewer passes goes on into more and ends as a run planned with them: issue
// 44's bonded digs, run one pass each first, go on into their second without running it again.
bool MorePassesOf(const Checkpoint& checkpoint, const Scene& scene) {
  if (!scene.dig.enabled) return false;
  const Scene stored = LoadSceneText(checkpoint.scene_path, checkpoint.scene_yaml);
  if (!stored.dig.enabled || scene.dig.passes < stored.dig.passes) return false;
  const auto document = [&](const std::string& text) {
    YAML::Node root = yaml_input::ParseDocument(scene.path, text);
    yaml_input::ApplySets(&root, yaml_input::SetsOf(text));
    yaml_input::ApplySets(&root, {"dig.passes=0"});
    YAML::Emitter out;
    out << root;
    return std::string(out.c_str());
  };
  return document(checkpoint.scene_yaml) == document(scene.yaml_text);
}

}  // namespace

int RunScene(const Scene& scene, const RunOptions& options) {
  RefuseOutputOverScene(options.output, scene);
  CheckOutputPath(options.output);
  InstallStopHandlers();
  // The output first, before any work: refused when it is one of the run's inputs (above) or
  // another process writes it (locked from here to the end).
  const bool checkpoints = options.checkpoint_every > 0 || options.resume;
  if (checkpoints && scene.arm.enabled) {
    throw InputError(scene.path +
                     ": arm: a run with an arm cannot be checkpointed or resumed "
                     "(Bullet's solver state is not saved)");
  }
  const std::string restart = CheckpointPath(options.output);
  // The scene's driver (none without a dig): the kinematic path, the arm coupled to the DEM or
  // the arm on a wrench table, which brings its own wrench and needs no bed.
  std::unique_ptr<ScoopDriver> driver = MakeScoopDriver(scene);
  const bool needs_bed = !driver || driver->OwnStep() == 0;
  World world(scene, options.threads);
  world.mutable_system().set_adaptive_threads(options.adaptive_threads);
  // Bonds may force a smaller step than the contact's (issue 44): say which one rules.
  if (scene.bed.bonds.enabled && !options.quiet)
    Status("scoopsim: %s\n", TimeStepLine(scene).c_str());
  if (options.resume) {
    const Checkpoint checkpoint = ReadCheckpoint(restart);
    if (checkpoint.scene_yaml != scene.yaml_text && !MorePassesOf(checkpoint, scene)) {
      throw InputError(restart + ": made from another scene text than " + scene.path +
                       "'s (changed since?); resume with the scene it was made from (or with "
                       "more dig.passes, --set dig.passes=N)");
    }
    const OutputCursor cursor = DecodeCursor(checkpoint.output_state, restart);
    world.OpenOutput(options.output, &cursor);
    world.ResumeFrom(checkpoint, std::move(driver), restart);
    Status("scoopsim: going on from %s at t = %.6g s\n", restart.c_str(), checkpoint.time);
  } else {
    world.OpenOutput(options.output);
    if (needs_bed) {
      world.KeepPour(PourPath(options.output));
      if (!scene.bed.file.empty()) {
        world.LoadBed(scene.bed.file);  // already resolved against the scene's folder
      } else {
        SettleReport r;
        const int status = world.Pour(options.quiet, &r);
        if (status != kExitOk) return status;
        world.BondBed();  // bed.bonds: the settled bed's bonds (LoadBed makes them for a file)
      }
    }
    if (driver) world.StartDig(std::move(driver));
  }
  RunControl control = Control(options);
  if (checkpoints) {
    control.checkpoint_every = options.checkpoint_every;
    control.checkpoint_path = restart;
    control.checkpoint_at_stop_after = true;
  }
  const RunResult result = world.Run(control);
  if (checkpoints && result.exit_status == kExitOk && !result.stopped_after) {
    std::error_code ignored;
    std::filesystem::remove(restart, ignored);  // ended: nothing to go on from
  }
  if (options.dig_summary) *options.dig_summary = world.dig_summary();
  return result.exit_status;
}

int RunShapeStudy(const Scene& scene, const ShapeStudyOptions& options) {
  namespace fs = std::filesystem;
  InstallStopHandlers();
  if (!scene.dig.enabled) throw InputError(scene.path + ": study shape: the scene needs a dig");
  RefuseArmScene(scene, "study shape");
  std::vector<std::string> names =
      options.templates.empty() ? BuiltinClumpNames() : options.templates;
  std::vector<dem::ClumpTemplate> templates;
  for (const std::string& name : names) {
    const dem::ClumpTemplate* t = dem::FindBuiltinTemplate(name);
    for (const dem::ClumpTemplate& own : scene.clump_templates)
      if (own.name == name) t = &own;
    if (t == nullptr) {
      std::string known;
      for (const std::string& k : BuiltinClumpNames()) known += (known.empty() ? "" : ", ") + k;
      for (const dem::ClumpTemplate& own : scene.clump_templates) known += ", " + own.name;
      throw InputError("study shape: --templates: expected names among " + known + ", got " + name);
    }
    templates.push_back(*t);
  }
  if (!scene.bed.file.empty() && !options.quiet)
    std::fprintf(stderr, "scoopsim: study shape makes a bed per template; bed.file is not used\n");

  H5Output out(options.output, scene.yaml_text, SCOOPSIM_VERSION, scene.output.flush_seconds);
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : ",") + name;
  out.SetAttribute("study", std::string("shape"));
  out.SetAttribute("templates", list);
  struct Row {
    std::string name;
    double spheres_per_clump, clumps, spheres, time_step, bed_wall, dig_wall, dig_cpu, peak, mean,
        overlap;
  };
  std::vector<Row> rows;
  int status = 0;
  for (const dem::ClumpTemplate& t : templates) {
    Scene s = WithClumpBed(scene, t);
    s.output.snapshot_every = 0;  // the study file holds the wrench, not the particles
    World world(s, options.threads);
    std::fprintf(stderr,
                 "scoopsim: study shape: %s, %zu sphere(s) a clump, %lld clumps, dt %.3g s\n",
                 t.name.c_str(), t.radii.size(), static_cast<long long>(s.bed.count), s.time_step);
    // The bed: cached in bed_dir when asked, else made.
    const auto bed0 = std::chrono::steady_clock::now();
    const std::string bed_path =
        options.bed_dir.empty() ? "" : (fs::path(options.bed_dir) / (t.name + ".h5")).string();
    // A cached bed is used only when it was made from this very scene text: a bed of another
    // box or count would silently change the study.
    bool cached = !bed_path.empty() && fs::exists(bed_path);
    if (cached && BedSceneYaml(bed_path) != s.yaml_text) {
      cached = false;
      std::fprintf(stderr,
                   "scoopsim: study shape: %s was made from another scene; making it again\n",
                   bed_path.c_str());
    }
    if (cached) {
      world.LoadBed(bed_path);
    } else {
      SettleReport r;
      status = world.Pour(options.quiet, &r);
      if (status != kExitOk) break;
      if (!bed_path.empty()) SaveBed(bed_path, world.system(), s.yaml_text);
    }
    const dem::System* system = &world.system();
    const double bed_wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - bed0).count();
    // The dig, into the template's group.
    const double clumps = static_cast<double>(system->clumps().size());
    const double spheres = static_cast<double>(system->particles().size());
    out.SetGroup("/" + t.name);
    const auto dig0 = std::chrono::steady_clock::now();
    const double cpu0 = CpuSeconds();
    world.UseOutput(&out);
    world.StartDig(MakeScoopDriver(s));
    RunControl control;
    control.quiet = options.quiet;
    status = world.Run(control).exit_status;
    const DigSummary& summary = world.dig_summary();
    const double dig_cpu = CpuSeconds() - cpu0;
    const double dig_wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - dig0).count();
    const Row row{t.name,
                  static_cast<double>(t.radii.size()),
                  clumps,
                  spheres,
                  s.time_step,
                  bed_wall,
                  dig_wall,
                  dig_cpu,
                  summary.peak_force,
                  summary.mean_force,
                  summary.peak_overlap};
    out.SetAttribute("spheres_per_clump", row.spheres_per_clump);
    out.SetAttribute("clumps", clumps);
    out.SetAttribute("spheres", spheres);
    out.SetAttribute("time_step", s.time_step);
    out.SetAttribute("bed_wall_s", bed_wall);
    out.SetAttribute("dig_wall_s", dig_wall);
    out.SetAttribute("dig_cpu_s", dig_cpu);
    out.SetAttribute("steps", static_cast<double>(summary.steps));
    out.SetAttribute("peak_force", summary.peak_force);
    out.SetAttribute("mean_force", summary.mean_force);
    out.SetAttribute("peak_torque", summary.peak_torque);
    out.SetAttribute("peak_overlap", summary.peak_overlap);
    out.SetStateHash(system->StateHash());
    out.SetGroup("");
    const double table[10] = {row.spheres_per_clump, clumps,  spheres,  row.time_step, row.bed_wall,
                              row.dig_wall,          dig_cpu, row.peak, row.mean,      row.overlap};
    const char* columns[10] = {"spheres_per_clump", "clumps",      "spheres",   "time_step",
                               "bed_wall_s",        "dig_wall_s",  "dig_cpu_s", "peak_force",
                               "mean_force",        "peak_overlap"};
    for (int k = 0; k < 10; ++k) out.AppendRow(std::string("/table/") + columns[k], &table[k], 1);
    rows.push_back(row);
    out.Flush();
    if (status != 0) break;
  }
  out.Close();
  std::fprintf(
      stderr,
      "scoopsim: study shape (wrench in the world frame about the scoop CoM; mean after "
      "first contact):\n"
      "| template | spheres/clump | clumps | spheres | dt [s] | bed wall [s] | dig wall [s] "
      "| dig CPU [s] | peak abs(F) [N] | mean abs(F) [N] | peak overlap [%% of diameter] |\n"
      "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const Row& r : rows)
    std::fprintf(stderr,
                 "| %s | %.0f | %.0f | %.0f | %.3g | %.1f | %.1f | %.1f | %.4g | %.4g | %.1f |\n",
                 r.name.c_str(), r.spheres_per_clump, r.clumps, r.spheres, r.time_step, r.bed_wall,
                 r.dig_wall, r.dig_cpu, r.peak, r.mean, 100.0 * r.overlap);
  std::fprintf(stderr, "scoopsim: wrote %s\n", options.output.c_str());
  return status;
}

int BenchSettle(const BenchSettleOptions& options) {
  namespace fs = std::filesystem;
  // The benchmark bed of the foundation issue (scenes/bench_settle.yaml): snow spheres of 3.5 mm
  // (paper Table 6) on a 0.2 m x 0.1 m floor, gravity 1.3, dt = 0.2 t_R, skin 0.875 mm. Only the
  // particle count changes with --particles; the box grows in height to hold the loose fill.
  const std::string source = SCOOPSIM_SOURCE_DIR;
  Scene scene = LoadScene(source + "/scenes/bench_settle.yaml");
  if (options.particles <= 0) throw InputError("bench settle: --particles: expected > 0");
  if (options.steps <= 0) throw InputError("bench settle: --steps: expected > 0");
  const double r = scene.bed.radius_max;
  const double area = (scene.box_max.x - scene.box_min.x) * (scene.box_max.y - scene.box_min.y);
  const double loose_height =
      options.particles * 4.0 / 3.0 * M_PI * r * r * r / (scene.bed.fill_fraction * area);
  scene.bed.count = options.particles;
  scene.box_max.z = std::max(scene.box_max.z, scene.box_min.z + 1.2 * loose_height + 4 * r);

  const std::string dir = options.cache_dir.empty() ? source + "/bench/cache" : options.cache_dir;
  const std::string bed_path = dir + "/settle_" + std::to_string(options.particles) + ".h5";
  World world(scene, options.threads);
  if (fs::exists(bed_path)) {
    world.LoadBed(bed_path);
  } else {
    std::fprintf(stderr, "scoopsim bench: preparing %s (once)\n", bed_path.c_str());
    InstallStopHandlers();
    SettleReport r;
    const int status = world.Pour(false, &r);
    if (status != kExitOk && status != kExitNotSettled) return status;
    SaveBed(bed_path, world.system(), scene.yaml_text);
  }
  // The DEM step alone, as the settle benchmarks of other codes time theirs (no output rows).
  dem::System* system = &world.mutable_system();
  const int64_t n = static_cast<int64_t>(system->particles().size());
  const auto t0 = std::chrono::steady_clock::now();
  for (int64_t k = 0; k < options.steps; ++k) {
    const dem::StepStatus status = system->Step();
    if (!status.ok()) {
      Status("scoopsim: simulation unstable: %s\n", status.message.c_str());
      return kExitUnstable;
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const dem::NeighborStats ns = system->neighbor_stats();
  std::printf(
      "{\"bench\":\"settle\",\"particles\":%lld,\"steps\":%lld,\"threads\":%d,\"wall_s\":%.4f,"
      "\"particle_steps_per_s\":%.4g,\"contacts_per_particle\":%.3f,\"neighbor_builds\":%lld,"
      "\"peak_rss_mb\":%.1f,\"state_hash\":\"%016llx\"}\n",
      static_cast<long long>(n), static_cast<long long>(options.steps), system->num_threads(), wall,
      n * static_cast<double>(options.steps) / wall,
      (2.0 * ns.contacts + ns.wall_contacts) / std::max<int64_t>(n, 1),
      static_cast<long long>(ns.builds), PeakRssMb(),
      static_cast<unsigned long long>(system->StateHash()));
  return 0;
}

// The arm of `bench step --arm`: the ArmDriver of a coupled dig (sim/loop/arm_driver.h), on the
// bench scene given an arm of the URDF (`--set arm.urdf=URDF --set arm.d_term=implicit`: the
// lander's gains, the D term implicit, one Bullet step per DEM step) and a dig that holds the
// scoop buried at the box's centre, pushed by a constant 20 N along world -x at its origin. Each
// DEM step is one MotionAt (the arm's step: PID, wrench, Bullet's step, the fault monitor, the
// sensor, the scoop's pose and twist) and one Feedback, as in a coupled dig; the bed never sees
// the scoop, so its state is the plain run's.
struct BenchArm {
  Scene scene;
  std::unique_ptr<ArmDriver> driver;
  double dt = 0;
  int64_t steps = 0;
  double seconds = 0;  // spent stepping it [s]
  double sink = 0;     // keeps the pose and twist reads
  BenchArm(const std::string& scene_path, const std::string& urdf, const dem::System& bed) {
    std::error_code ec;
    const std::filesystem::path absolute = std::filesystem::absolute(urdf, ec);
    scene = LoadScene(scene_path,
                      {"arm.urdf=" + (ec ? urdf : absolute.string()), "arm.d_term=implicit"});
    if (scene.arm.model->dof() != 6)
      throw InputError(urdf + ": bench step --arm: expected the lander's six-joint arm");
    DigSpec& dig = scene.dig;
    dig.enabled = true;
    if (dig.scoop.geometry.vertices.empty()) {
      // No scoop in the bench scene: the path places l_scoop's origin, a small triangle there.
      dig.scoop.geometry.vertices = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}};
      dig.scoop.geometry.triangles = {{0, 1, 2}};
    }
    dig.start_buried = true;
    dig.trajectory = TrajectorySpec{};
    dig.trajectory.initial_pitch = M_PI / 2;  // blade down, as the paper's paths
    dig.trajectory.pivot_start = 0.5 * (scene.box_min + scene.box_max);
    dig.trajectory.moves = {Hold("hold", 1.0)};  // then held: the bench may run past it
    scene.arm.substeps = 1;
    scene.arm.implicit_d = true;
    driver = std::make_unique<ArmDriver>(scene, /*announce=*/false);
    // The bed's top as its surface (the arm's base stands on it, under the scoop).
    double surface = scene.box_min.z;
    const dem::Particles& p = bed.particles();
    for (size_t i = 0; i < p.size(); ++i) surface = std::max(surface, p.x[i].z + p.radius[i]);
    dt = scene.time_step;
    BedContext context{&dig.scoop.geometry, surface, surface, dt, 0.0};
    driver->BeginPass(1, context);
  }
  void Step() {
    const auto t0 = std::chrono::steady_clock::now();
    const double tau = static_cast<double>(++steps) * dt;
    const dem::MeshMotion m = driver->MotionAt(tau);
    dem::MeshWrench w;
    w.force = {-20, 0, 0};  // at the scoop's origin: no torque about it
    driver->Feedback(tau, w);
    sink += m.pose.position.x + m.velocity.x;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
};

int BenchStep(const BenchStepOptions& options) {
  if (options.checkpoint.empty() == options.scene.empty())
    throw InputError("bench step: expected a SCENE or --checkpoint FILE (one of them)");
  if (!options.checkpoint.empty() && !options.arm.empty())
    throw InputError(options.checkpoint + ": bench step --arm: expected a SCENE, not a checkpoint");
  std::unique_ptr<Checkpoint> checkpoint;
  if (!options.checkpoint.empty())
    checkpoint = std::make_unique<Checkpoint>(ReadCheckpoint(options.checkpoint));
  const Scene scene =
      checkpoint ? LoadSceneText(checkpoint->scene_path,
                                 yaml_input::TextWithSets(checkpoint->scene_yaml, options.sets))
                 : LoadScene(options.scene, options.sets);
  if (!checkpoint && scene.bed.file.empty())
    throw InputError(options.scene + ": bed.file: expected a saved bed");
  World world(scene, options.threads);
  if (checkpoint) {
    // No output: the steps write nothing (World::Step without one).
    world.ResumeFrom(*checkpoint, MakeScoopDriver(scene, /*announce=*/false), options.checkpoint);
    checkpoint.reset();  // the state's bytes, no longer needed
    if (!options.sets.empty()) world.mutable_system().Touch();  // lists of the changed scene
  } else {
    world.LoadState(scene.bed.file);
  }
  const dem::System* system = &world.system();
  std::unique_ptr<BenchArm> bench_arm;
  if (!options.arm.empty())
    bench_arm = std::make_unique<BenchArm>(options.scene, options.arm, world.system());
  auto run = [&](int64_t steps, int64_t* awake_sum) {
    for (int64_t k = 0; k < steps; ++k) {
      const dem::StepStatus status = world.Step();
      if (!status.ok()) {
        Status("scoopsim: simulation unstable: %s\n", status.message.c_str());
        return false;
      }
      if (bench_arm) bench_arm->Step();
      *awake_sum += system->neighbor_stats().awake;
    }
    return true;
  };
  int64_t awake = 0;
  if (!run(options.warm, &awake)) return kExitUnstable;
  const dem::NeighborStats before = system->neighbor_stats();
  awake = 0;
  const dem::PhaseTimes phases0 = system->phase_times();
  if (bench_arm) bench_arm->seconds = 0;
  const auto t0 = std::chrono::steady_clock::now();
  if (!run(options.steps, &awake)) return kExitUnstable;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const dem::NeighborStats ns = system->neighbor_stats();
  const double steps = static_cast<double>(std::max<int64_t>(options.steps, 1));
  const std::string phases = PhaseJson(PhasesSince(system->phase_times(), phases0), wall, steps);
  std::string arm_json;
  if (bench_arm) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "\"arm_ms_per_step\":%.5f,",
                  1e3 * bench_arm->seconds / steps);
    arm_json = buffer;
  }
  std::printf(
      "{\"bench\":\"step\",\"particles\":%zu,\"awake_per_step\":%.0f,\"steps\":%lld,"
      "\"threads\":%d,\"wall_s\":%.4f,\"ms_per_step\":%.4f,\"awake_particle_steps_per_s\":%.4g,"
      "\"neighbor_builds\":%lld,\"partial_builds\":%lld,\"near_builds\":%lld,\"near_pairs\":%lld,"
      "\"contacts\":%lld,%s,%s"
      "\"peak_rss_mb\":%.1f,"
      "\"state_hash\":\"%016llx\"}\n",
      system->particles().size(), awake / steps, static_cast<long long>(options.steps),
      system->num_threads(), wall, 1e3 * wall / steps, awake / wall,
      static_cast<long long>(ns.builds - before.builds),
      static_cast<long long>(ns.partial_builds - before.partial_builds),
      static_cast<long long>(ns.near_builds - before.near_builds),
      static_cast<long long>(ns.near_pairs), static_cast<long long>(ns.contacts), phases.c_str(),
      arm_json.c_str(), PeakRssMb(), static_cast<unsigned long long>(system->StateHash()));
  return 0;
}

}  // namespace sim

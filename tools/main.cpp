// scoopsim: the command-line program.
//   scoopsim bed SCENE -o BED.h5            fill the scene's box, settle, save the bed
//   scoopsim run SCENE -o OUT.h5            load (or make) the bed and run for scene.duration
//   scoopsim bench settle --particles N --steps S
//   scoopsim run SCENE --frames DIR [--every S] [--video]   PNG frames while running (render/)
//   scoopsim render OUT.h5 --frames DIR [--video] [--color-by F] [--camera PRESET]
//   scoopsim bench render --bed BED.h5 --particles N --frames F [--threads T]
//   scoopsim study shape SCENE [-o OUT.h5] [--templates A,B] [--beds DIR]   the shape study
//   scoopsim study balovnev SCENE [-o OUT.h5] [--phi-deg P] [--delta-deg D] [--buried]
//                                 [--model textbook|lander|both]
//                                            the dig against Balovnev's model (table + PNG)
//   scoopsim study particle-size SCENE [-o DIR] [--sizes A,B] [--beds N] [--prior CSV] [--case I]
//   [--list]
//                                            the particle-size study (eq. 5-7; CSV, table, PNGs)
//   scoopsim sweep SWEEP.yaml -o DIR; scoopsim table build|query|export-csv (tools/sweep_cli.h)
//   scoopsim arm info URDF [--gravity G]     the parsed arm and its gravity torques
// Exit status: sim/input/exit_status.h (0 success, 1 runtime failure, 2 bad input, 3 unstable, 4 bed
// not settled, 130 stopped by a signal).
// Bad input is reported as one line on stderr: "scoopsim: FILE:LINE: KEY: expected ..., got ...".
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "arm/arm_model.h"
#include "render/bench.h"
#include "render/camera.h"
#include "render/frames.h"
#include "render/saved_run.h"
#include "sim/files/checkpoint.h"
#include "sim/studies/commands.h"
#include "sim/input/exit_status.h"
#include "sim/loop/preflight.h"
#include "sim/files/saved_run.h"
#include "sim/input/scene.h"
#include "tools/arm_info.h"
#include "tools/cli_checks.h"
#include "tools/sweep_cli.h"

namespace {

using sim::kExitFailure;
using sim::kExitInput;
constexpr int kMaxThreads = 4096;  // same bound as the scene's `threads`

// Messages are printed on one line of text, whatever they contain (a binary file's bytes, quoted
// back, included): line breaks become spaces, other control bytes and bytes that are not UTF-8
// become \xNN.
std::string OneLine(const std::string& message) {
  std::string out;
  const auto* b = reinterpret_cast<const unsigned char*>(message.data());
  const size_t n = message.size();
  for (size_t i = 0; i < n;) {
    const unsigned char c = b[i];
    // Length of a well-formed UTF-8 sequence starting here (1 for ASCII), or 0.
    size_t len = c < 0x80           ? 1
                 : (c >> 5) == 0x6  ? 2
                 : (c >> 4) == 0xE  ? 3
                 : (c >> 3) == 0x1E ? 4
                                    : 0;
    if (c >= 0x80 && c < 0xC2) len = 0;  // a continuation byte, or an overlong lead
    if (len > 1) {
      if (i + len > n) len = 0;
      for (size_t k = 1; k < len; ++k)
        if ((b[i + k] >> 6) != 0x2) len = 0;
    }
    if (c == '\n' || c == '\r') {
      out += ' ';
    } else if (len == 0 || (len == 1 && (c < 0x20 || c == 0x7F) && c != '\t')) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      out += hex;
      len = 1;
    } else {
      out.append(message, i, len);
    }
    i += len;
  }
  return out;
}

// --set KEY=VALUE (repeatable): a scene key overridden from the command line, checked as the
// scene is (sim::LoadScene).
void AddSetOption(CLI::App* command, std::vector<std::string>* sets) {
  command
      ->add_option("--set", *sets,
                   "KEY=VALUE: override a scene key (dotted, e.g. dig.bite_depth=0.01; VALUE is "
                   "YAML); repeatable")
      ->take_all()
      ->allow_extra_args(false);
}

// Options shared by `bed` and `run`.
struct SceneCommand {
  std::string scene;
  std::string output;
  int threads = 0;
  bool quiet = false;
  bool fixed_threads = false;
  CLI::Option* threads_option = nullptr;
  CLI::Option* scene_option = nullptr;
  CLI::Option* output_option = nullptr;
  std::vector<std::string> sets;  // --set KEY=VALUE overrides of scene keys

  // `governed`: the command steps one world under the thread governor (`bed`, `run`), so it
  // offers --fixed-threads; the studies keep their threads fixed and do not.
  void AddTo(CLI::App* command, const std::string& default_output, bool governed) {
    output = default_output;
    scene_option =
        command->add_option("SCENE", scene, "Scene file (YAML), e.g. scenes/default.yaml")
            ->required();
    output_option =
        command->add_option("-o,--output", output, "Output HDF5 file (parent folders are created)")
            ->capture_default_str();
    threads_option =
        command
            ->add_option("--threads", threads,
                         "Worker threads; 0 = all cores (default: the scene's `threads`, else 0)")
            ->check(CLI::Range(0, kMaxThreads));
    command->add_flag("-q,--quiet", quiet, "No progress output");
    AddSetOption(command, &sets);
    if (governed) {
      command->add_flag("--fixed-threads", fixed_threads,
                        "Use exactly --threads workers every step (default: fewer while timing "
                        "shows fewer faster, as when another process holds a core; results are "
                        "the same)");
    }
  }

  // The scene, and run options where the command line overrides the scene (a study's options
  // too: any struct with threads, output and quiet).
  template <typename T>
  T OptionsAs(const sim::Scene& loaded) const {
    T options;
    options.threads = threads_option->count() > 0 ? threads : loaded.threads;
    options.output = output;
    options.quiet = quiet;
    return options;
  }
  sim::RunOptions Options(const sim::Scene& loaded) const {
    sim::RunOptions options = OptionsAs<sim::RunOptions>(loaded);
    options.adaptive_threads = !fixed_threads;  // a study keeps its threads fixed
    return options;
  }
};

// Frame options shared by `run --frames` and `render`.
struct FramesArgs {
  std::string dir;
  double every = 0;
  bool video = false;
  std::string color_by;
  std::string camera;
  std::string color_range;

  void AddTo(CLI::App* command, bool required, bool with_every) {
    CLI::Option* frames = command->add_option("--frames", dir,
                                              "Write numbered PNG frames (frame_000000.png, ...) "
                                              "into this folder");
    if (required) frames->required();
    if (with_every) {
      command
          ->add_option("--every", every,
                       "Simulated seconds between frames (default: the scene's render.every, "
                       "else 0.05 in a dig and output.interval in a plain run)")
          ->check(tools::FinitePositive("s"));
    }
    command->add_flag("--video", video, "Also assemble DIR.mp4 with ffmpeg (when installed)");
    command
        ->add_option("--color-by", color_by,
                     "speed|depth|material|force (force: run --frames only, snapshots store "
                     "no forces; default: the scene's)")
        ->check(CLI::IsMember({"speed", "depth", "material", "force"}));
    command->add_option("--color-range", color_range,
                        "LO,HI: the colour range of every frame (default: run: from the scene, "
                        "render: the whole run's)");
    std::string presets;
    for (const std::string& p : render::CameraPresetNames())
      presets += (presets.empty() ? "" : "|") + p;
    command->add_option("--camera", camera, "Camera preset: " + presets + " (default: the scene's)")
        ->check(CLI::IsMember(render::CameraPresetNames()));
  }

  // Options from the scene's render block with the command line's overrides.
  render::FrameOptions Options(const sim::RenderSpec& spec, int threads) const {
    std::error_code ec;
    if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
      throw sim::InputError("--frames " + dir + ": expected a folder for the frames, got a file");
    sim::RenderSpec s = spec;
    if (!color_by.empty()) s.color_by = color_by;
    if (!camera.empty()) s.camera_preset = camera;
    render::FrameOptions options = render::FrameOptionsFromSpec(s);
    options.dir = dir;
    options.threads = threads;
    if (!color_range.empty()) {
      // Two finite numbers, LO < HI, and nothing else.
      const char* text = color_range.c_str();
      char* end = nullptr;
      const double lo = std::strtod(text, &end);
      const bool comma = end != text && *end == ',';
      const char* second = comma ? end + 1 : end;
      const double hi = comma ? std::strtod(second, &end) : 0.0;
      if (!comma || end == second || *end != '\0' || !std::isfinite(lo) || !std::isfinite(hi) ||
          !(lo < hi)) {
        throw sim::InputError("--color-range: expected LO,HI, two numbers with LO < HI, got " +
                              color_range);
      }
      options.settings.range_min = lo;
      options.settings.range_max = hi;
      options.range_given = true;
    }
    return options;
  }

  // --video: DIR.mp4 next to the folder (DIR/frames.mp4 for "." or ".."), at 25 frames/s;
  // says why when there is none.
  void MaybeVideo() const {
    if (!video) return;
    const std::filesystem::path folder = std::filesystem::path(dir).lexically_normal();
    const std::string name = folder.filename().string();
    const std::string mp4 = (name.empty() || name == "." || name == "..")
                                ? (folder / "frames.mp4").string()
                                : (folder.parent_path() / (name + ".mp4")).string();
    std::string message;
    render::AssembleVideo(dir, mp4, 25, &message);
    std::fprintf(stderr, "scoopsim: %s\n", message.c_str());
  }
};

// CLI11 reads an unknown command as a missing one ("A subcommand is required"): the command
// words of argv are checked first, each against the commands of the one before it. Returns the
// refusal's line, or "" when every word is a known command (options are CLI11's to judge).
std::string UnknownCommand(CLI::App* app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";
    const std::vector<CLI::App*> commands = app->get_subcommands([](CLI::App*) { return true; });
    if (commands.empty()) return "";  // the command's own arguments follow
    std::string names;
    CLI::App* next = nullptr;
    for (CLI::App* c : commands) {
      names += (names.empty() ? "" : ", ") + c->get_name();
      if (c->check_name(word)) next = c;
    }
    if (next == nullptr) {
      const std::string where = app->get_parent() == nullptr ? "" : app->get_name() + " ";
      return "scoopsim: " + where + "COMMAND: expected one of " + names + ", got '" +
             OneLine(word) + "' (see --help)";
    }
    app = next;
  }
  return "";
}

// The scene's warnings (sim::Scene::warnings), one line each on stderr.
void PrintWarnings(const sim::Scene& scene) {
  for (const std::string& w : scene.warnings)
    std::fprintf(stderr, "scoopsim: warning: %s\n", OneLine(w).c_str());
}

// Logical cores, for LP_NUM_THREADS when the run uses all of them.
int AllCores() {
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? static_cast<int>(n) : 1;
}

int Main(int argc, char** argv) {
  CLI::App app{"scoopsim: DEM simulation of a lander scoop digging granular terrain"};
  app.set_version_flag("--version", std::string("scoopsim ") + SCOOPSIM_VERSION);
  app.require_subcommand(1);
  // A command-line error is bad input: one line, as for a scene.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "scoopsim: " + OneLine(e.what()) + " (see --help)\n";
  });

  SceneCommand bed_args;
  CLI::App* bed = app.add_subcommand("bed", "Fill the scene's box, settle the bed and save it");
  bed_args.AddTo(bed, "out/bed.h5", true);

  SceneCommand run_args;
  CLI::App* run = app.add_subcommand(
      "run", "Run a scene for its duration (loads bed.file, or makes the bed first)");
  run_args.AddTo(run, "out/run.h5", true);
  double run_stop_after = 0;
  run->add_option("--stop-after", run_stop_after,
                  "Stop after this many simulated seconds, the output closed as on SIGINT "
                  "(default: at the scene's end)")
      ->check(tools::FinitePositive("s"));
  double run_checkpoint_every = 0;
  run->add_option("--checkpoint-every", run_checkpoint_every,
                  "Keep the run's whole state in OUT.restart.h5 every this many seconds of wall "
                  "time (and when stopped by a signal); removed when the run ends")
      ->check(tools::FinitePositive("s"));
  std::string run_resume;
  run->add_option("--resume", run_resume,
                  "Go on from OUT.restart.h5 of this output (SCENE, if given, must be the one it "
                  "was made from); the output ends as the uninterrupted run's")
      ->option_text("OUT.h5");
  run_args.scene_option->required(false);
  FramesArgs run_frames;
  run_frames.AddTo(run, false, true);

  std::string check_scene;
  CLI::App* check = app.add_subcommand(
      "check",
      "Check a scene as `run` would before any work (the scene, its mesh and bed file, the time "
      "step, the steps and memory the run needs, the dig's path) and print the forecast");
  check->add_option("SCENE", check_scene, "Scene file (YAML)")->required();
  std::vector<std::string> check_sets;
  AddSetOption(check, &check_sets);

  FramesArgs render_frames;
  std::string render_input;
  bool render_quiet = false;
  int render_threads = 0;
  CLI::App* render_cmd = app.add_subcommand(
      "render",
      "Render the particle snapshots of a saved run (scoopsim run -o OUT.h5) as PNG frames");
  render_cmd->add_option("OUT.h5", render_input, "A run's HDF5 file")->required();
  render_frames.AddTo(render_cmd, true, false);
  render_cmd
      ->add_option("--threads", render_threads,
                   "Rasteriser threads (LP_NUM_THREADS); 0 = all cores")
      ->check(CLI::Range(0, kMaxThreads));
  render_cmd->add_flag("-q,--quiet", render_quiet, "No progress output");

  CLI::App* study = app.add_subcommand("study", "Studies of the reference paper");
  study->require_subcommand(1);
  // A study: a subcommand with a scene, an output, --threads and --quiet.
  auto add_study = [study](SceneCommand* args, const char* name, const char* help,
                           const char* output) {
    CLI::App* command = study->add_subcommand(name, help);
    args->AddTo(command, output, false);
    return command;
  };
  SceneCommand shape_args;
  CLI::App* shape = add_study(
      &shape_args, "shape",
      "Shape-complexity study (paper Table 3, Fig. 8): the scene's dig on a bed of each clump "
      "template; wrench and wall time per template in one HDF5 file",
      "out/shape_study.h5");
  std::vector<std::string> shape_templates;
  std::string shape_beds;
  shape
      ->add_option("--templates", shape_templates,
                   "Clump templates, comma separated (default: tetra1,tetra4,tetra8,tetra12)")
      ->delimiter(',');
  shape->add_option("--beds", shape_beds,
                    "Folder of the beds: DIR/<template>.h5 is loaded if present and made from "
                    "the same scene text, else made and saved there");

  SceneCommand balovnev_args;
  CLI::App* balovnev = add_study(
      &balovnev_args, "balovnev",
      "The scene's dig (pass 1) against Balovnev's analytical model (../shared/FACTS.md section "
      "7) along the same path: OUT.h5 (the dig), OUT.balovnev.csv, a table on stdout, "
      "OUT.balovnev.png",
      "out/balovnev.h5");
  double balovnev_phi = 44, balovnev_delta = 28, balovnev_rake = 10;
  bool balovnev_buried = false, balovnev_no_plot = false;
  balovnev->add_option("--phi-deg", balovnev_phi, "Internal friction angle phi [deg]")
      ->capture_default_str();
  balovnev
      ->add_option("--delta-deg", balovnev_delta, "Soil-tool friction angle delta [deg], <= phi")
      ->capture_default_str();
  balovnev->add_option("--rake-deg", balovnev_rake, "Rake angle beta of the blade [deg]")
      ->capture_default_str();
  balovnev->add_flag("--buried", balovnev_buried, "b = 1: the bucket is buried (default b = 0)");
  balovnev->add_flag("--no-plot", balovnev_no_plot, "Do not draw OUT.balovnev.png");
  std::string balovnev_model = "both";
  balovnev
      ->add_option("--model", balovnev_model,
                   "Which Balovnev the table and plot show: textbook (FACTS 7's formula, the "
                   "bed's gamma), lander (the OceanWATERS plugin's variant: its constants, "
                   "branch and caps) or both; the CSV always has both")
      ->capture_default_str()
      ->check(CLI::IsMember({"textbook", "lander", "both"}));

  // The particle-size study: its cases are a sweep (resumed, MPI, --case), so its options are a
  // sweep's rather than a run's.
  std::string size_scene;
  sim::SizeStudyOptions size_options;
  bool size_no_plot = false;
  CLI::App* size = study->add_subcommand(
      "particle-size",
      "Particle-size study (paper eq. 5-7, Fig. 3-6): the scene's dig on beds of each diameter "
      "(the same solid volume), several beds each, run as a sweep; MPE of the smoothed peak "
      "|F| and |T| against the finest size, the largest size within 20%: DIR/size_study.csv, "
      "a table on stdout, DIR/size_*.png");
  size->add_option("SCENE", size_scene,
                   "A size-study scene: spheres of one diameter, poured, one pass "
                   "(scenes/paper/size_S10.yaml)")
      ->required();
  size->add_option("-o,--output", size_options.dir, "Output folder")->capture_default_str();
  size->add_option("--sizes", size_options.sizes_mm,
                   "Diameters [mm], comma separated (default: the study's eq. 5, "
                   "2,2.5,3.25,4,5.25,6.5,8.25,10)")
      ->delimiter(',')
      ->check(tools::FinitePositive("mm"));  // each diameter as written ('' was read as 0)
  size->add_option("--beds", size_options.beds, "Independent beds (seeds) per size")
      ->capture_default_str();
  size->add_option("--smooth-s", size_options.smooth_s,
                   "Window of the centred moving mean of |F| and |T| [s]")
      ->capture_default_str();
  size->add_option("--case", size_options.only_case,
                   "Run only case I (0-based, the order of --list): one task of a job array")
      ->check(tools::WholeNonNegative());
  size->add_option("--threads", size_options.threads,
                   "DEM threads per case; 0 = all cores (default: the scene's `threads` when "
                   "plain, 1 per rank under mpirun)")
      ->check(CLI::Range(0, kMaxThreads));
  size->add_option("--prior", size_options.priors,
                   "An earlier run's DIR/size_study.csv (same scene, same --smooth-s): its sizes "
                   "join this run's in eq. 6-7 without being run again (rows only: peaks, beds, "
                   "cost); repeatable, a size run here or in an earlier file wins")
      ->check(CLI::ExistingFile);
  size->add_option("--checkpoint-every", size_options.checkpoint_every,
                   "Keep a running case's state (its pour so far, or its dig) every this many "
                   "seconds of wall time and when stopped, so that the same command goes on "
                   "from there bit for bit; 0 = never")
      ->capture_default_str()
      ->check(tools::FiniteNonNegative("s"));
  size->add_flag("--list", size_options.list,
                 "Print the cases (index, name, settings, cost, where each stands in DIR) "
                 "and exit");
  size->add_flag("--no-plot", size_no_plot, "Do not draw DIR/size_*.png");
  size->add_flag("-q,--quiet", size_options.quiet, "No progress line within a case");

  CLI::App* bench = app.add_subcommand("bench", "Benchmarks");
  bench->require_subcommand(1);
  CLI::App* settle =
      bench->add_subcommand("settle", "Time the DEM step on a settled bed (prints one JSON line)");
  sim::BenchSettleOptions bench_options;
  bool bench_quiet = false;
  settle->add_option("--particles", bench_options.particles, "Number of spheres")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  settle->add_option("--steps", bench_options.steps, "Time steps to time")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  settle->add_option("--threads", bench_options.threads, "Worker threads; 0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  settle->add_flag("-q,--quiet", bench_quiet, "No progress output (the JSON line is kept)");
  CLI::App* step = bench->add_subcommand(
      "step", "Time a scene's step from its saved bed, e.g. a mid-dig state (one JSON line)");
  sim::BenchStepOptions step_options;
  step->add_option("SCENE", step_options.scene, "Scene file (YAML) with a bed file")->required();
  step->add_option("--warm", step_options.warm, "Steps run before the timing")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{1000000000}));
  step->add_option("--steps", step_options.steps, "Time steps to time")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  step->add_option("--threads", step_options.threads, "Worker threads; 0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  step->add_option("--arm", step_options.arm,
                   "A URDF (the lander's arm): step it once per DEM step beside the bed, its "
                   "time apart (arm_ms_per_step)");
  CLI::App* bench_render = bench->add_subcommand(
      "render",
      "Frames per second of the renderer at 1280x720, PNG writing included (one JSON line)");
  render::BenchRenderOptions render_bench;
  bench_render
      ->add_option("--bed", render_bench.bed,
                   "A bed file of `scoopsim bed` or a run's output: its last snapshot is drawn "
                   "(bench/run_render.sh makes one from scenes/settle_small.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  bench_render
      ->add_option("--particles", render_bench.particles,
                   "Number of spheres: copies of the bed side by side, the last cut short; 0 = "
                   "the bed's own")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{100000000}));
  bench_render->add_option("--frames", render_bench.frames, "Frames to time")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  bench_render
      ->add_option("--threads", render_bench.threads,
                   "Rasteriser threads (LP_NUM_THREADS); 0 = the environment's or all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  bench_render->add_option("--keep", render_bench.keep_dir,
                           "Write the frames into this folder and keep them (default: a temporary "
                           "folder, removed)");
  bench_render->add_flag("!--no-cull", render_bench.cull_hidden,
                         "Hand every particle to GL (no occlusion culling), to measure it");
  bench_render->add_option("--png-level", render_bench.png_level, "zlib level of the PNGs")
      ->capture_default_str()
      ->check(CLI::Range(0, 9));

  tools::SweepCommands sweep_commands;  // sweep, table build / query / export-csv
  sweep_commands.AddTo(&app);

  CLI::App* arm_cmd = app.add_subcommand("arm", "The arm alone (its URDF), without the DEM");
  arm_cmd->require_subcommand(1);
  CLI::App* arm_info = arm_cmd->add_subcommand(
      "info", "Print the parsed arm (joints, limits, masses) and gravity torques at named poses");
  std::string arm_urdf;
  double arm_gravity = 1.3;
  arm_info->add_option("URDF", arm_urdf, "The arm's URDF, e.g. assets/lander_arm.urdf")->required();
  arm_info->add_option("--gravity", arm_gravity, "Gravity [m/s^2] along -z of the base link")
      ->capture_default_str()
      ->check(tools::FiniteInRange(0, 1000, "m/s^2"));  // past it the torques overflow

  if (const std::string unknown = UnknownCommand(&app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "%s\n", unknown.c_str());
    return kExitInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every parse error is bad input.
    return app.exit(e) == 0 ? 0 : kExitInput;
  }

  try {
    if (*bed) {
      sim::Scene scene = sim::LoadScene(bed_args.scene, bed_args.sets);
      sim::Preflight(&scene, sim::Work::kBed);
      PrintWarnings(scene);
      return sim::MakeBed(scene, bed_args.Options(scene));
    }
    if (*run) {
      if (run_args.scene.empty() && run_resume.empty())
        throw sim::InputError("run: SCENE: expected a scene file (or --resume OUT.h5)");
      if (run_args.scene.empty() && !run_args.sets.empty())
        throw sim::InputError(
            "run: --set: expected a SCENE to set keys of (a run resumed without "
            "one goes on with its checkpoint's scene, the --set it had included)");
      if (!run_resume.empty() && run_args.output_option->count() > 0 &&
          run_args.output != run_resume)
        throw sim::InputError("run: -o " + run_args.output + " and --resume " + run_resume +
                              ": a resumed run writes the output it resumes; give one of them");
      // Resumed without SCENE: the scene text and path its checkpoint holds.
      sim::Scene scene =
          !run_args.scene.empty() ? sim::LoadScene(run_args.scene, run_args.sets) : [&] {
            const sim::Checkpoint c = sim::ReadCheckpoint(sim::CheckpointPath(run_resume));
            return sim::LoadSceneText(c.scene_path, c.scene_yaml);
          }();
      sim::Preflight(&scene, sim::Work::kRun);
      PrintWarnings(scene);
      sim::RunOptions options = run_args.Options(scene);
      options.stop_after = run_stop_after;
      options.checkpoint_every = run_checkpoint_every;
      if (!run_resume.empty()) {
        options.resume = true;
        options.output = run_resume;
      }
      std::unique_ptr<render::FrameSequence> frames;
      if (!run_frames.dir.empty()) {
        // The frames' folder would be made where the output goes ("Is a directory").
        std::error_code ec;
        const std::filesystem::path frames_at =
            std::filesystem::weakly_canonical(run_frames.dir, ec);
        if (!ec && frames_at == std::filesystem::weakly_canonical(options.output, ec)) {
          throw sim::InputError("--frames " + run_frames.dir +
                                ": expected a folder other than the output file (-o " +
                                options.output + ")");
        }
        // Checked before the renderer is made (an OpenGL context): at most a frame a step, a
        // spacing below the time step is a typo (1e-300 for 1e-3).
        options.frame_every = run_frames.every > 0 ? run_frames.every : scene.render.every;
        if (options.frame_every > 0 && options.frame_every < scene.time_step) {
          char text[96];
          std::snprintf(text, sizeof text,
                        ": expected at least the time step (%.6g s) between frames, got %.6g",
                        scene.time_step, options.frame_every);
          throw sim::InputError(
              (run_frames.every > 0 ? std::string("--every") : scene.path + ": render.every") +
              text);
        }
        // Rendering happens inside the run loop's frame callback, between steps: the DEM's
        // OpenMP threads are idle then, and llvmpipe gets as many threads as the DEM had.
        render::FrameOptions frame_options =
            run_frames.Options(scene.render, options.threads > 0 ? options.threads : AllCores());
        if (!frame_options.range_given) {
          render::SceneColorRange(scene, frame_options.settings.color_by,
                                  &frame_options.settings.range_min,
                                  &frame_options.settings.range_max);
        }
        frames = std::make_unique<render::FrameSequence>(frame_options);
        options.on_frame = [&frames](const sim::WorldView& view) { frames->Add(view); };
      }
      const int status = sim::RunScene(scene, options);
      if (frames) {
        std::fprintf(stderr, "scoopsim: %d frames in %s (%.0f ms draw + %.0f ms PNG a frame)\n",
                     frames->count(), run_frames.dir.c_str(),
                     1e3 * frames->draw_seconds() / std::max(frames->count(), 1),
                     1e3 * frames->png_seconds() / std::max(frames->count(), 1));
        run_frames.MaybeVideo();
      }
      return status;
    }
    if (*check) {
      sim::Scene scene = sim::LoadScene(check_scene, check_sets);
      const sim::RunForecast f = sim::Preflight(&scene, sim::Work::kRun);
      PrintWarnings(scene);
      std::printf(
          "%s: ok: %lld particles, time step %.4g s, %.4g s simulated in about %.3g "
          "steps, about %.3g MB of memory\n",
          check_scene.c_str(), static_cast<long long>(f.particles), f.time_step, f.simulated,
          f.steps, f.bytes / 1e6);
      return 0;
    }
    if (*render_cmd) {
      // Camera, colouring and size from the run's own scene (its `render:` block), then the
      // command line.
      const sim::RenderSpec spec = sim::SavedRun(render_input).Scene().render;
      render::FrameSequence frames(
          render_frames.Options(spec, render_threads > 0 ? render_threads : AllCores()));
      const int count = render::RenderSavedRun(render_input, &frames, render_quiet);
      std::fprintf(stderr, "scoopsim: %d frames in %s\n", count, render_frames.dir.c_str());
      render_frames.MaybeVideo();
      return 0;
    }
    if (*shape) {
      const sim::Scene scene = sim::LoadScene(shape_args.scene, shape_args.sets);
      auto options = shape_args.OptionsAs<sim::ShapeStudyOptions>(scene);
      options.templates = shape_templates;
      options.bed_dir = shape_beds;
      return sim::RunShapeStudy(scene, options);
    }
    if (*balovnev) {
      const sim::Scene scene = sim::LoadScene(balovnev_args.scene, balovnev_args.sets);
      auto options = balovnev_args.OptionsAs<sim::BalovnevStudyOptions>(scene);
      options.plot = !balovnev_no_plot;
      // The angles' domain, in the flags' own units (sim::Balovnev checks the rest).
      auto require = [](bool ok, const std::string& flag, const std::string& expected, double got) {
        if (!ok)
          throw sim::InputError("study balovnev: " + flag + ": expected " + expected + ", got " +
                                CLI::detail::to_string(got));
      };
      require(balovnev_phi > 0 && balovnev_phi < 90, "--phi-deg", "a value in (0, 90)",
              balovnev_phi);
      require(balovnev_delta >= 0 && balovnev_delta <= balovnev_phi, "--delta-deg",
              "a value in [0, --phi-deg]", balovnev_delta);
      require(balovnev_rake > 0 && balovnev_rake <= 90, "--rake-deg", "a value in (0, 90]",
              balovnev_rake);
      constexpr double kDeg = 3.14159265358979323846 / 180;
      options.soil.friction_angle = balovnev_phi * kDeg;
      options.soil.tool_friction_angle = balovnev_delta * kDeg;
      options.tool.rake = balovnev_rake * kDeg;
      options.buried = balovnev_buried;
      options.show_textbook = balovnev_model != "lander";
      options.show_lander = balovnev_model != "textbook";
      return sim::RunBalovnevStudy(scene, options);
    }
    if (*size) {
      size_options.plot = !size_no_plot;
      return sim::RunSizeStudy(size_scene, size_options);
    }
    if (*settle) return sim::BenchSettle(bench_options);
    if (*step) return sim::BenchStep(step_options);
    if (*bench_render) return render::BenchRender(render_bench);
    if (const int status = sweep_commands.Run(); status >= 0) return status;
    if (*arm_info) {
      tools::PrintArmInfo(arm_urdf, arm_gravity, stdout);
      return 0;
    }
  } catch (const arm::ArmModelError& e) {
    std::fprintf(stderr, "scoopsim: %s\n", OneLine(e.what()).c_str());
    return kExitInput;
  } catch (const sim::InputError& e) {
    // An error found after the scene was loaded (its preflight) about a key given by --set names
    // the --set, as LoadScene's own errors do.
    const std::vector<std::string>& sets = *bed        ? bed_args.sets
                                           : *run      ? run_args.sets
                                           : *check    ? check_sets
                                           : *shape    ? shape_args.sets
                                           : *balovnev ? balovnev_args.sets
                                                       : check_sets;
    std::fprintf(stderr, "scoopsim: %s\n", OneLine(sim::NamingSet(e, sets).what()).c_str());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scoopsim: error: %s\n", OneLine(e.what()).c_str());
    return kExitFailure;
  }
  return kExitInput;  // unreachable: a subcommand is required
}

// Waiting OpenMP threads spin briefly, then sleep, unless the user chose otherwise
// (OMP_WAIT_POLICY or GOMP_SPINCOUNT): GOMP_SPINCOUNT=10000. On a quiet host the step's many
// short parallel regions follow each other within that spin, so the second thread is there at
// once (a 20,000-sphere dig 1.62-1.68x faster on two threads, as fast as spinning; sleeping
// threads: 1.00x, every region waking the other thread); with one core busy a wait costs at most
// that spin and the thread governor (dem/thread_governor.h) drops to one thread (2 threads 0.98-
// 1.04x one thread's time, sleeping 1.08-1.17x, spinning 10x): bench/busy_core.sh,
// ARCHITECTURE.md "A busy core". The runtime reads its settings when it loads, before main, so
// the program starts itself again once with the setting in its environment. `scoopsim bench`
// keeps the runtime's default (spinning), as the journal's rows were measured.
void BriefSpinByDefault(int argc, char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr) return;
  if (argc > 1 && std::string(argv[1]) == "bench") return;
  ::setenv("GOMP_SPINCOUNT", "10000", 1);
  ::execv("/proc/self/exe", argv);  // returns only on failure: go on with the runtime's default
}

}  // namespace

int main(int argc, char** argv) {
  BriefSpinByDefault(argc, argv);
  return Main(argc, argv);
}

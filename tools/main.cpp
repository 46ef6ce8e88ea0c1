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
//   scoopsim calibrate bonds [--material M] [--scales A,B] ...   bond strength -> UCS, sigma_t, E
// Each subcommand is one function (its options, then how it runs), registered in kCommands; Main
// sets them all up, parses, and runs the one given.
// Exit status: sim/input/exit_status.h (0 success, 1 runtime failure, 2 bad input, 3 unstable, 4
// bed not settled, 130 stopped by a signal). Bad input is reported as one line on stderr:
// "scoopsim: FILE:LINE: KEY: expected ..., got ...".
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
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
#include "sim/files/saved_run.h"
#include "sim/input/exit_status.h"
#include "sim/input/scene.h"
#include "sim/input/yaml_input.h"
#include "sim/loop/preflight.h"
#include "sim/studies/calibrate.h"
#include "sim/studies/commands.h"
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
                     "speed|depth|material|force|broken_bonds (force: run --frames only, "
                     "snapshots store no forces; broken_bonds: a bonded bed's; default: the "
                     "scene's)")
        ->check(CLI::IsMember({"speed", "depth", "material", "force", "broken_bonds"}));
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

// ---------------------------------------------------------------------------------------------
// The subcommands: one function each, which adds the command and its options under `parent` and
// returns how to run it; Main sets them all up from kCommands and runs the one given.

// A subcommand set up on the command line.
struct Command {
  std::function<bool()> given;  // it is the command the command line named
  std::function<int()> run;     // runs it (after parsing); its exit status
  // Its --set overrides (none: null): an InputError found after the scene's load about a key
  // they set names the --set, as LoadScene's own errors do.
  std::shared_ptr<const std::vector<std::string>> sets;
};
using Setup = Command (*)(CLI::App* parent);

std::function<bool()> Given(const CLI::App* command) {
  return [command] { return static_cast<bool>(*command); };
}
// The --set overrides of a command's arguments, kept alive with them.
template <typename Args>
std::shared_ptr<const std::vector<std::string>> SetsOf(const std::shared_ptr<Args>& args) {
  return std::shared_ptr<const std::vector<std::string>>(args, &args->sets);
}

Command Bed(CLI::App* parent) {
  CLI::App* command =
      parent->add_subcommand("bed", "Fill the scene's box, settle the bed and save it");
  auto args = std::make_shared<SceneCommand>();
  args->AddTo(command, "out/bed.h5", true);
  return {Given(command),
          [args] {
            sim::Scene scene = sim::LoadScene(args->scene, args->sets);
            sim::Preflight(&scene, sim::Work::kBed);
            PrintWarnings(scene);
            return sim::MakeBed(scene, args->Options(scene));
          },
          SetsOf(args)};
}

struct RunArgs : SceneCommand {
  double stop_after = 0;
  double checkpoint_every = 0;
  std::string resume;
  FramesArgs frames;
};

int RunCommand(const RunArgs& args) {
  if (args.scene.empty() && args.resume.empty())
    throw sim::InputError("run: SCENE: expected a scene file (or --resume OUT.h5)");
  if (!args.resume.empty() && args.output_option->count() > 0 && args.output != args.resume)
    throw sim::InputError("run: -o " + args.output + " and --resume " + args.resume +
                          ": a resumed run writes the output it resumes; give one of them");
  // Resumed without SCENE: the scene text and path its checkpoint holds, and any --set after them
  // (RunScene takes only more dig.passes: `--resume OUT --set dig.passes=N`).
  sim::Scene scene = !args.scene.empty() ? sim::LoadScene(args.scene, args.sets) : [&] {
    const sim::Checkpoint c = sim::ReadCheckpoint(sim::CheckpointPath(args.resume));
    // A --set the checkpoint's text already ends its key with (the same dig.passes=N given again
    // when a resumed run is resumed once more) is not added a second time.
    const std::vector<std::string> held = sim::yaml_input::SetsOf(c.scene_yaml);
    std::vector<std::string> sets;
    for (const std::string& set : args.sets) {
      const std::string key = set.substr(0, set.find('='));
      std::string last;
      for (const std::string& h : held)
        if (h.substr(0, h.find('=')) == key) last = h;
      if (last != set) sets.push_back(set);
    }
    return sim::LoadSceneText(c.scene_path, sim::yaml_input::TextWithSets(c.scene_yaml, sets));
  }();
  sim::Preflight(&scene, sim::Work::kRun);
  PrintWarnings(scene);
  sim::RunOptions options = args.Options(scene);
  options.stop_after = args.stop_after;
  options.checkpoint_every = args.checkpoint_every;
  if (!args.resume.empty()) {
    options.resume = true;
    options.output = args.resume;
  }
  const FramesArgs& run_frames = args.frames;
  std::unique_ptr<render::FrameSequence> frames;
  if (!run_frames.dir.empty()) {
    // The frames' folder would be made where the output goes ("Is a directory").
    std::error_code ec;
    const std::filesystem::path frames_at = std::filesystem::weakly_canonical(run_frames.dir, ec);
    if (!ec && frames_at == std::filesystem::weakly_canonical(options.output, ec)) {
      throw sim::InputError("--frames " + run_frames.dir +
                            ": expected a folder other than the output file (-o " + options.output +
                            ")");
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
          (run_frames.every > 0 ? std::string("--every") : scene.path + ": render.every") + text);
    }
    // Rendering happens inside the run loop's frame callback, between steps: the DEM's
    // OpenMP threads are idle then, and llvmpipe gets as many threads as the DEM had.
    render::FrameOptions frame_options =
        run_frames.Options(scene.render, options.threads > 0 ? options.threads : AllCores());
    if (!frame_options.range_given) {
      render::SceneColorRange(scene, frame_options.settings.color_by,
                              &frame_options.settings.range_min, &frame_options.settings.range_max);
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

Command Run(CLI::App* parent) {
  CLI::App* command = parent->add_subcommand(
      "run", "Run a scene for its duration (loads bed.file, or makes the bed first)");
  auto args = std::make_shared<RunArgs>();
  args->AddTo(command, "out/run.h5", true);
  command
      ->add_option("--stop-after", args->stop_after,
                   "Stop after this many simulated seconds from the run's start (a resumed run's "
                   "first start), the output closed as on SIGINT; with --checkpoint-every, "
                   "OUT.restart.h5 keeps the state there to go on from (default: at the scene's "
                   "end)")
      ->check(tools::FinitePositive("s"));
  command
      ->add_option("--checkpoint-every", args->checkpoint_every,
                   "Keep the run's whole state in OUT.restart.h5 every this many seconds of wall "
                   "time (and when stopped by a signal); removed when the run ends")
      ->check(tools::FinitePositive("s"));
  command
      ->add_option("--resume", args->resume,
                   "Go on from OUT.restart.h5 of this output (SCENE, if given, must be the one it "
                   "was made from, or it with more dig passes: --set dig.passes=N); the output "
                   "ends as the uninterrupted run's")
      ->option_text("OUT.h5");
  args->scene_option->required(false);
  args->frames.AddTo(command, false, true);
  return {Given(command), [args] { return RunCommand(*args); }, SetsOf(args)};
}

Command Check(CLI::App* parent) {
  CLI::App* command = parent->add_subcommand(
      "check",
      "Check a scene as `run` would before any work (the scene, its mesh and bed file, the time "
      "step, the steps and memory the run needs, the dig's path) and print the forecast");
  struct Args {
    std::string scene;
    std::vector<std::string> sets;
  };
  auto args = std::make_shared<Args>();
  command->add_option("SCENE", args->scene, "Scene file (YAML)")->required();
  AddSetOption(command, &args->sets);
  return {Given(command),
          [args] {
            sim::Scene scene = sim::LoadScene(args->scene, args->sets);
            const sim::RunForecast f = sim::Preflight(&scene, sim::Work::kRun);
            PrintWarnings(scene);
            std::printf(
                "%s: ok: %lld particles, time step %.4g s (%s rules), %.4g s simulated in about "
                "%.3g steps, about %.3g MB of memory\n",
                args->scene.c_str(), static_cast<long long>(f.particles), f.time_step,
                f.time_step_rule, f.simulated, f.steps, f.bytes / 1e6);
            if (!f.bond_note.empty()) std::printf("%s\n", f.bond_note.c_str());
            return 0;
          },
          SetsOf(args)};
}

Command Render(CLI::App* parent) {
  struct Args {
    FramesArgs frames;
    std::string input;
    bool quiet = false;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = parent->add_subcommand(
      "render",
      "Render the particle snapshots of a saved run (scoopsim run -o OUT.h5) as PNG frames");
  command->add_option("OUT.h5", args->input, "A run's HDF5 file")->required();
  args->frames.AddTo(command, true, false);
  command
      ->add_option("--threads", args->threads, "Rasteriser threads (LP_NUM_THREADS); 0 = all cores")
      ->check(CLI::Range(0, kMaxThreads));
  command->add_flag("-q,--quiet", args->quiet, "No progress output");
  return {Given(command),
          [args] {
            // Camera, colouring and size from the run's own scene (its `render:` block), then the
            // command line.
            const sim::RenderSpec spec = sim::SavedRun(args->input).Scene().render;
            render::FrameSequence frames(
                args->frames.Options(spec, args->threads > 0 ? args->threads : AllCores()));
            const int count = render::RenderSavedRun(args->input, &frames, args->quiet);
            std::fprintf(stderr, "scoopsim: %d frames in %s\n", count, args->frames.dir.c_str());
            args->frames.MaybeVideo();
            return 0;
          },
          nullptr};
}

// A study: a subcommand with a scene, an output, --threads and --quiet.
CLI::App* AddStudy(CLI::App* study, SceneCommand* args, const char* name, const char* help,
                   const char* output) {
  CLI::App* command = study->add_subcommand(name, help);
  args->AddTo(command, output, false);
  return command;
}

Command Shape(CLI::App* study) {
  struct Args : SceneCommand {
    std::vector<std::string> templates;
    std::string beds;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = AddStudy(
      study, args.get(), "shape",
      "Shape-complexity study (paper Table 3, Fig. 8): the scene's dig on a bed of each clump "
      "template; wrench and wall time per template in one HDF5 file",
      "out/shape_study.h5");
  command
      ->add_option("--templates", args->templates,
                   "Clump templates, comma separated (default: tetra1,tetra4,tetra8,tetra12)")
      ->delimiter(',');
  command->add_option("--beds", args->beds,
                      "Folder of the beds: DIR/<template>.h5 is loaded if present and made from "
                      "the same scene text, else made and saved there");
  return {Given(command),
          [args] {
            const sim::Scene scene = sim::LoadScene(args->scene, args->sets);
            auto options = args->OptionsAs<sim::ShapeStudyOptions>(scene);
            options.templates = args->templates;
            options.bed_dir = args->beds;
            return sim::RunShapeStudy(scene, options);
          },
          SetsOf(args)};
}

struct BalovnevArgs : SceneCommand {
  double phi = 44, delta = 28, rake = 10;  // [deg]
  bool buried = false, no_plot = false;
  std::string model = "both";
};

int BalovnevCommand(const BalovnevArgs& args) {
  const sim::Scene scene = sim::LoadScene(args.scene, args.sets);
  auto options = args.OptionsAs<sim::BalovnevStudyOptions>(scene);
  options.plot = !args.no_plot;
  // The angles' domain, in the flags' own units (sim::Balovnev checks the rest).
  auto require = [](bool ok, const std::string& flag, const std::string& expected, double got) {
    if (!ok)
      throw sim::InputError("study balovnev: " + flag + ": expected " + expected + ", got " +
                            CLI::detail::to_string(got));
  };
  require(args.phi > 0 && args.phi < 90, "--phi-deg", "a value in (0, 90)", args.phi);
  require(args.delta >= 0 && args.delta <= args.phi, "--delta-deg", "a value in [0, --phi-deg]",
          args.delta);
  require(args.rake > 0 && args.rake <= 90, "--rake-deg", "a value in (0, 90]", args.rake);
  constexpr double kDeg = 3.14159265358979323846 / 180;
  options.soil.friction_angle = args.phi * kDeg;
  options.soil.tool_friction_angle = args.delta * kDeg;
  options.tool.rake = args.rake * kDeg;
  options.buried = args.buried;
  options.show_textbook = args.model != "lander";
  options.show_lander = args.model != "textbook";
  return sim::RunBalovnevStudy(scene, options);
}

Command Balovnev(CLI::App* study) {
  auto args = std::make_shared<BalovnevArgs>();
  CLI::App* command = AddStudy(
      study, args.get(), "balovnev",
      "The scene's dig (pass 1) against Balovnev's analytical model (../shared/FACTS.md section "
      "7) along the same path: OUT.h5 (the dig), OUT.balovnev.csv, a table on stdout, "
      "OUT.balovnev.png",
      "out/balovnev.h5");
  command->add_option("--phi-deg", args->phi, "Internal friction angle phi [deg]")
      ->capture_default_str();
  command->add_option("--delta-deg", args->delta, "Soil-tool friction angle delta [deg], <= phi")
      ->capture_default_str();
  command->add_option("--rake-deg", args->rake, "Rake angle beta of the blade [deg]")
      ->capture_default_str();
  command->add_flag("--buried", args->buried, "b = 1: the bucket is buried (default b = 0)");
  command->add_flag("--no-plot", args->no_plot, "Do not draw OUT.balovnev.png");
  command
      ->add_option("--model", args->model,
                   "Which Balovnev the table and plot show: textbook (FACTS 7's formula, the "
                   "bed's gamma), lander (the OceanWATERS plugin's variant: its constants, "
                   "branch and caps) or both; the CSV always has both")
      ->capture_default_str()
      ->check(CLI::IsMember({"textbook", "lander", "both"}));
  return {Given(command), [args] { return BalovnevCommand(*args); }, SetsOf(args)};
}

// The particle-size study: its cases are a sweep (resumed, MPI, --case), so its options are a
// sweep's rather than a run's.
Command ParticleSize(CLI::App* study) {
  struct Args {
    std::string scene;
    sim::SizeStudyOptions options;
    bool no_plot = false;
  };
  auto args = std::make_shared<Args>();
  sim::SizeStudyOptions& options = args->options;
  CLI::App* command = study->add_subcommand(
      "particle-size",
      "Particle-size study (paper eq. 5-7, Fig. 3-6): the scene's dig on beds of each diameter "
      "(the same solid volume), several beds each, run as a sweep; MPE of the smoothed peak "
      "|F| and |T| against the finest size, the largest size within 20%: DIR/size_study.csv, "
      "a table on stdout, DIR/size_*.png");
  command
      ->add_option("SCENE", args->scene,
                   "A size-study scene: spheres of one diameter, poured, one pass "
                   "(scenes/paper/size_S10.yaml)")
      ->required();
  command->add_option("-o,--output", options.dir, "Output folder")->capture_default_str();
  command
      ->add_option("--sizes", options.sizes_mm,
                   "Diameters [mm], comma separated (default: the study's eq. 5, "
                   "2,2.5,3.25,4,5.25,6.5,8.25,10)")
      ->delimiter(',')
      ->check(tools::FinitePositive("mm"));  // each diameter as written ('' was read as 0)
  command->add_option("--beds", options.beds, "Independent beds (seeds) per size")
      ->capture_default_str();
  command
      ->add_option("--smooth-s", options.smooth_s,
                   "Window of the centred moving mean of |F| and |T| [s]")
      ->capture_default_str();
  command
      ->add_option("--case", options.only_case,
                   "Run only case I (0-based, the order of --list): one task of a job array")
      ->check(tools::WholeNonNegative());
  command
      ->add_option("--threads", options.threads,
                   "DEM threads per case; 0 = all cores (default: the scene's `threads` when "
                   "plain, 1 per rank under mpirun)")
      ->check(CLI::Range(0, kMaxThreads));
  command
      ->add_option("--prior", options.priors,
                   "An earlier run's DIR/size_study.csv (same scene, same --smooth-s): its sizes "
                   "join this run's in eq. 6-7 without being run again (rows only: peaks, beds, "
                   "cost); repeatable, a size run here or in an earlier file wins")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--checkpoint-every", options.checkpoint_every,
                   "Keep a running case's state (its pour so far, or its dig) every this many "
                   "seconds of wall time and when stopped, so that the same command goes on "
                   "from there bit for bit; 0 = never")
      ->capture_default_str()
      ->check(tools::FiniteNonNegative("s"));
  command->add_flag("--list", options.list,
                    "Print the cases (index, name, settings, cost, where each stands in DIR) "
                    "and exit");
  command->add_flag("--no-plot", args->no_plot, "Do not draw DIR/size_*.png");
  command->add_flag("-q,--quiet", options.quiet, "No progress line within a case");
  return {Given(command),
          [args] {
            args->options.plot = !args->no_plot;
            return sim::RunSizeStudy(args->scene, args->options);
          },
          nullptr};
}

Command BenchSettle(CLI::App* bench) {
  struct Args {
    sim::BenchSettleOptions options;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command =
      bench->add_subcommand("settle", "Time the DEM step on a settled bed (prints one JSON line)");
  command->add_option("--particles", args->options.particles, "Number of spheres")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  command->add_option("--steps", args->options.steps, "Time steps to time")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  command->add_option("--threads", args->options.threads, "Worker threads; 0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  command->add_flag("-q,--quiet", args->quiet, "No progress output (the JSON line is kept)");
  return {Given(command), [args] { return sim::BenchSettle(args->options); }, nullptr};
}

Command BenchStep(CLI::App* bench) {
  auto options = std::make_shared<sim::BenchStepOptions>();
  CLI::App* command = bench->add_subcommand(
      "step", "Time a scene's step from its saved bed, e.g. a mid-dig state (one JSON line)");
  command->add_option("SCENE", options->scene, "Scene file (YAML) with a bed file");
  command->add_option("--checkpoint", options->checkpoint,
                      "A run's checkpoint (OUT.restart.h5) instead of SCENE: step on from it, "
                      "under the scene it holds (a mid-dig state)");
  command->add_option("--set", options->sets,
                      "KEY=VALUE: override a scene key (repeatable); on a checkpoint the lists "
                      "are made again from the changed scene before the first step");
  command->add_option("--warm", options->warm, "Steps run before the timing")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{1000000000}));
  command->add_option("--steps", options->steps, "Time steps to time")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{1}, int64_t{1000000000}));
  command->add_option("--threads", options->threads, "Worker threads; 0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  command->add_option("--arm", options->arm,
                      "A URDF (the lander's arm): step it once per DEM step beside the bed, its "
                      "time apart (arm_ms_per_step)");
  return {Given(command), [options] { return sim::BenchStep(*options); }, nullptr};
}

Command BenchRender(CLI::App* bench) {
  auto options = std::make_shared<render::BenchRenderOptions>();
  CLI::App* command = bench->add_subcommand(
      "render",
      "Frames per second of the renderer at 1280x720, PNG writing included (one JSON line)");
  command
      ->add_option("--bed", options->bed,
                   "A bed file of `scoopsim bed` or a run's output: its last snapshot is drawn "
                   "(bench/run_render.sh makes one from scenes/settle_small.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  command
      ->add_option("--particles", options->particles,
                   "Number of spheres: copies of the bed side by side, the last cut short; 0 = "
                   "the bed's own")
      ->capture_default_str()
      ->check(CLI::Range(int64_t{0}, int64_t{100000000}));
  command->add_option("--frames", options->frames, "Frames to time")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  command
      ->add_option("--threads", options->threads,
                   "Rasteriser threads (LP_NUM_THREADS); 0 = the environment's or all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  command->add_option("--keep", options->keep_dir,
                      "Write the frames into this folder and keep them (default: a temporary "
                      "folder, removed)");
  command->add_flag("!--no-cull", options->cull_hidden,
                    "Hand every particle to GL (no occlusion culling), to measure it");
  command->add_option("--png-level", options->png_level, "zlib level of the PNGs")
      ->capture_default_str()
      ->check(CLI::Range(0, 9));
  return {Given(command), [options] { return render::BenchRender(*options); }, nullptr};
}

// `sweep` and `table build|query|export-csv` (tools/sweep_cli.h).
Command SweepAndTable(CLI::App* parent) {
  auto commands = std::make_shared<tools::SweepCommands>();
  commands->AddTo(parent);
  const CLI::App* sweep = parent->get_subcommand("sweep");
  const CLI::App* table = parent->get_subcommand("table");
  return {[sweep, table] { return *sweep || *table; }, [commands] { return commands->Run(); },
          nullptr};
}

Command ArmInfo(CLI::App* arm) {
  struct Args {
    std::string urdf;
    double gravity = 1.3;  // [m/s^2]
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = arm->add_subcommand(
      "info", "Print the parsed arm (joints, limits, masses) and gravity torques at named poses");
  command->add_option("URDF", args->urdf, "The arm's URDF, e.g. assets/lander_arm.urdf")
      ->required();
  command->add_option("--gravity", args->gravity, "Gravity [m/s^2] along -z of the base link")
      ->capture_default_str()
      ->check(tools::FiniteInRange(0, 1000, "m/s^2"));  // past it the torques overflow
  return {Given(command),
          [args] {
            tools::PrintArmInfo(args->urdf, args->gravity, stdout);
            return 0;
          },
          nullptr};
}

// A saved run as a ROS 1 bag: tools/export_rosbag.py (python3-rosbag), run as the studies run
// their plot scripts; its own one-line errors come first on stderr.
Command ExportRosbag(CLI::App* exporter) {
  struct Args {
    std::string run, out;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = exporter->add_subcommand(
      "rosbag", "Write a run of an arm scene (RUN.h5) as a ROS 1 bag (docs/ros.md)");
  command->add_option("RUN", args->run, "A run file of a scene with an arm: block (.h5)")
      ->required();
  command->add_option("-o,--output", args->out, "The bag to write (.bag)")->required();
  return {Given(command),
          [args] {
            const int status = sim::RunToolScript("export_rosbag.py", {args->run, "-o", args->out});
            return status == 0 ? sim::kExitOk : status == 2 ? sim::kExitInput : kExitFailure;
          },
          nullptr};
}

// `scoopsim calibrate bonds`: the bond parameters -> UCS, Brazilian tensile strength and E of a
// bonded sample (sim/studies/calibrate.h).
Command CalibrateBonds(CLI::App* calibrate) {
  struct Args {
    sim::BondCalibrationOptions options;
    double friction_angle_deg = 0;
    int threads = 1;
  };
  auto args = std::make_shared<Args>();
  sim::BondCalibrationOptions& o = args->options;
  o.bond.tensile_strength = 2e4;  // sigma_c / G = 2e-3 at the materials' G = 1e7 Pa
  o.bond.cohesion = 2e4;
  CLI::App* command = calibrate->add_subcommand(
      "bonds",
      "Bond calibration (issue 44; Potyondy & Cundall 2004, Int. J. Rock Mech. Min. Sci. 41, "
      "1329, section 3): a dense random packing of the material's spheres, bonded (dem/bond.h), "
      "crushed between gripped ends as a prism (H = 2 W: unconfined compression, UCS = P_peak / "
      "W^2, and Young's modulus E from the stress against the strain of the sample's middle "
      "half), the same prism pulled apart (direct tension, sigma_t = P_peak / W^2) and a disk "
      "gripped at two 30 deg flats (Brazilian test, sigma_t = 2 P_peak / (pi D t), ISRM 1978), "
      "once per strength scale: a CSV table (-o) and a line per row on stdout. "
      "The strengths are proportional to the bond strengths: to aim at a literature value, scale "
      "the bond strengths by its ratio to a measured row (docs/bonds.md); the modulus sets E and, "
      "with the particles' G, the time step. Targets: polycrystalline "
      "ice at -10 to -20 C has a compressive strength of 5-25 MPa and a tensile strength of "
      "0.7-3.1 MPa (Petrovic 2003, J. Mater. Sci. 38, 1-6, doi:10.1023/A:1021134128038); snow, "
      "an open cellular form of ice, is far weaker (Petrovic 2003).");
  command->add_option("--material", o.material, "A material of the materials file")
      ->capture_default_str();
  command->add_option("--materials", o.materials_path,
                      "Materials file (default: the source tree's scenes/materials.yaml)");
  command
      ->add_option("--shear-modulus", o.shear_modulus,
                   "G of the particles [Pa] (default: the material's): the Hertz contacts "
                   "between the spheres, in parallel with the bonds")
      ->check(tools::FinitePositive("Pa"));
  command->add_option("--radius", o.sample.radius, "Mean sphere radius r [m]")
      ->capture_default_str()
      ->check(tools::FinitePositive("m"));
  command->add_option("--spread", o.sample.spread, "Radii uniform in r (1 -/+ spread)")
      ->capture_default_str();
  command->add_option("--particles", o.sample.particles, "Spheres per sample, about")
      ->capture_default_str();
  command->add_option("--seed", o.sample.seed, "Seed of the packing")->capture_default_str();
  command
      ->add_option("--modulus", o.bond.modulus,
                   "Bond modulus E_b [Pa] (default: the particles' Young's modulus 2 G (1 + nu))")
      ->check(tools::FinitePositive("Pa"));
  command->add_option("--radius-multiplier", o.bond.radius_multiplier, "Bond radius lambda [-]")
      ->capture_default_str();
  command->add_option("--stiffness-ratio", o.bond.stiffness_ratio, "k_n / k_s [-]")
      ->capture_default_str();
  command
      ->add_option("--tensile-strength", o.bond.tensile_strength,
                   "Bond tensile strength sigma_c at scale 1 [Pa] (inf: unbreakable)")
      ->capture_default_str();
  command
      ->add_option("--cohesion", o.bond.cohesion,
                   "Bond cohesion c at scale 1 [Pa] (inf: unbreakable)")
      ->capture_default_str();
  command->add_option("--friction-angle", args->friction_angle_deg, "Bond friction angle phi [deg]")
      ->capture_default_str();
  command->add_option("--damping-ratio", o.bond.damping_ratio, "Bond damping, of critical [-]")
      ->capture_default_str();
  command
      ->add_option("--gap-fraction", o.gap_fraction,
                   "Bond the spheres whose surfaces are closer than this x r [-]")
      ->capture_default_str();
  command
      ->add_option("--scales", o.scales,
                   "Strength scales, comma separated: each row multiplies the tensile strength "
                   "and cohesion by one")
      ->delimiter(',');
  command
      ->add_option("--rayleigh-fraction", o.test.rayleigh_fraction,
                   "dt = min(this x t_R, the bond's critical step)")
      ->capture_default_str();
  command
      ->add_option("--speed-factor", o.test.speed_factor,
                   "Grip speed over the quasi-static one (the gripped ends close by sigma_c / E_b "
                   "in 100 wave transits of the sample)")
      ->capture_default_str();
  command
      ->add_option("--max-strain", o.test.max_strain,
                   "Strain limit: stop at this strain of the grips")
      ->capture_default_str();
  command
      ->add_option("--stop-fraction", o.test.stop_fraction,
                   "Stop once the load has fallen below this fraction of its peak")
      ->capture_default_str();
  command->add_flag("--rate-check", o.rate_check,
                    "Run the first scale again at half the speed and report the change");
  command->add_option("--threads", args->threads, "DEM threads; 0 = all cores")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxThreads));
  command->add_option("-o,--output", o.output, "The CSV table")->capture_default_str();
  command->add_flag("-q,--quiet", o.quiet, "No sample lines on stderr");
  return {Given(command),
          [args] {
            sim::BondCalibrationOptions options = args->options;
            constexpr double kDeg = 3.14159265358979323846 / 180;
            options.bond.friction_angle = args->friction_angle_deg * kDeg;
            options.test.threads = args->threads > 0 ? args->threads : AllCores();
            return sim::RunBondCalibration(options);
          },
          nullptr};
}

// Commands that hold subcommands (`scoopsim study shape`), made when their first one is added.
struct Group {
  const char* name;
  const char* help;
};
constexpr Group kGroups[] = {
    {"study", "Studies of the reference paper"},
    {"bench", "Benchmarks"},
    {"arm", "The arm alone (its URDF), without the DEM"},
    {"export", "A saved run in other tools' formats"},
    {"calibrate", "Calibrations of the material models against laboratory tests"},
};

// Every subcommand, in the order of --help: its group ("" for a top-level command) and setup.
struct Entry {
  const char* group;
  Setup setup;
};
constexpr Entry kCommands[] = {
    {"", Bed},
    {"", Run},
    {"", Check},
    {"", Render},
    {"study", Shape},
    {"study", Balovnev},
    {"study", ParticleSize},
    {"bench", BenchSettle},
    {"bench", BenchStep},
    {"bench", BenchRender},
    {"", SweepAndTable},
    {"arm", ArmInfo},
    {"export", ExportRosbag},
    {"calibrate", CalibrateBonds},
};

int Main(int argc, char** argv) {
  CLI::App app{"scoopsim: DEM simulation of a lander scoop digging granular terrain"};
  app.set_version_flag("--version", std::string("scoopsim ") + SCOOPSIM_VERSION);
  app.require_subcommand(1);
  // A command-line error is bad input: one line, as for a scene.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "scoopsim: " + OneLine(e.what()) + " (see --help)\n";
  });
  std::vector<Command> commands;
  std::map<std::string, CLI::App*> groups;
  for (const Entry& entry : kCommands) {
    CLI::App* parent = &app;
    if (*entry.group != '\0') {
      CLI::App*& group = groups[entry.group];
      if (group == nullptr) {
        const Group* g = std::find_if(std::begin(kGroups), std::end(kGroups), [&](const Group& g) {
          return std::string(g.name) == entry.group;
        });
        group = app.add_subcommand(g->name, g->help);
        group->require_subcommand(1);
      }
      parent = group;
    }
    commands.push_back(entry.setup(parent));
  }

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

  const auto given =
      std::find_if(commands.begin(), commands.end(), [](const Command& c) { return c.given(); });
  if (given == commands.end()) return kExitInput;  // unreachable: a subcommand is required
  try {
    return given->run();
  } catch (const arm::ArmModelError& e) {
    std::fprintf(stderr, "scoopsim: %s\n", OneLine(e.what()).c_str());
    return kExitInput;
  } catch (const sim::InputError& e) {
    const sim::InputError named = given->sets ? sim::NamingSet(e, *given->sets) : e;
    std::fprintf(stderr, "scoopsim: %s\n", OneLine(named.what()).c_str());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scoopsim: error: %s\n", OneLine(e.what()).c_str());
    return kExitFailure;
  }
}

// Waiting OpenMP threads spin briefly, then sleep, unless the user chose otherwise
// (OMP_WAIT_POLICY or GOMP_SPINCOUNT): GOMP_SPINCOUNT=10000. On a quiet host the step's many
// short parallel regions follow each other within that spin, so the second thread is there at
// once (a 20,000-sphere dig 1.62-1.68x faster on two threads, as fast as spinning; sleeping
// threads: 1.00x, every region waking the other thread); with one core busy a wait costs at most
// that spin and the thread governor (dem/thread_governor.h) drops to one thread (2 threads 0.98-
// 1.04x one thread's time, sleeping 1.08-1.17x, spinning 10x): bench/busy_core.sh,
// docs/dem.md "A busy core". The runtime reads its settings when it loads, before main, so
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

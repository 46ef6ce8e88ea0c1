// scoopsim: the command-line program.
//   scoopsim bed SCENE -o BED.h5            fill the scene's box, settle, save the bed
//   scoopsim run SCENE -o OUT.h5            load (or make) the bed and run for scene.duration
//   scoopsim bench settle --particles N --steps S
// Exit status: 0 success, 1 runtime failure, 2 bad input (scene, materials file or command line);
// the commands' own statuses pass through (sim/runner.cpp: 3 unstable, 4 not settled, 130 stopped).
// Bad input is reported as one line on stderr: "scoopsim: FILE:LINE: KEY: expected ..., got ...".
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "sim/runner.h"
#include "sim/scene.h"

namespace {

constexpr int kExitInput = 2;
constexpr int kExitFailure = 1;
constexpr int kMaxThreads = 4096;  // same bound as the scene's `threads`

// Messages are printed on one line, whatever they contain.
std::string OneLine(std::string message) {
  for (char& c : message) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return message;
}

// Creates the folder an output file goes into (nothing to do for a bare file name).
void MakeParentDirectories(const std::string& output) {
  const std::filesystem::path parent = std::filesystem::path(output).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
}

// Options shared by `bed` and `run`.
struct SceneCommand {
  std::string scene;
  std::string output;
  int threads = 0;
  bool quiet = false;
  CLI::Option* threads_option = nullptr;

  void AddTo(CLI::App* command, const std::string& default_output) {
    output = default_output;
    command->add_option("SCENE", scene, "Scene file (YAML), e.g. scenes/default.yaml")->required();
    command->add_option("-o,--output", output, "Output HDF5 file (parent folders are created)")
        ->capture_default_str();
    threads_option =
        command
            ->add_option("--threads", threads,
                         "Worker threads; 0 = all cores (default: the scene's `threads`, else 0)")
            ->check(CLI::Range(0, kMaxThreads));
    command->add_flag("-q,--quiet", quiet, "No progress output");
  }

  // The scene, and run options where the command line overrides the scene.
  sim::RunOptions Options(const sim::Scene& loaded) const {
    sim::RunOptions options;
    options.threads = threads_option->count() > 0 ? threads : loaded.threads;
    options.output = output;
    options.quiet = quiet;
    return options;
  }
};

int Main(int argc, char** argv) {
  CLI::App app{"scoopsim: DEM simulation of a lander scoop digging granular terrain"};
  app.set_version_flag("--version", std::string("scoopsim ") + SCOOPSIM_VERSION);
  app.require_subcommand(1);

  SceneCommand bed_args;
  CLI::App* bed = app.add_subcommand("bed", "Fill the scene's box, settle the bed and save it");
  bed_args.AddTo(bed, "out/bed.h5");

  SceneCommand run_args;
  CLI::App* run = app.add_subcommand(
      "run", "Run a scene for its duration (loads bed.file, or makes the bed first)");
  run_args.AddTo(run, "out/run.h5");

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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every parse error is bad input.
    return app.exit(e) == 0 ? 0 : kExitInput;
  }

  try {
    if (*bed) {
      const sim::Scene scene = sim::LoadScene(bed_args.scene);
      MakeParentDirectories(bed_args.output);
      return sim::MakeBed(scene, bed_args.Options(scene));
    }
    if (*run) {
      const sim::Scene scene = sim::LoadScene(run_args.scene);
      MakeParentDirectories(run_args.output);
      return sim::RunScene(scene, run_args.Options(scene));
    }
    if (*settle) return sim::BenchSettle(bench_options);
  } catch (const sim::InputError& e) {
    std::fprintf(stderr, "scoopsim: %s\n", OneLine(e.what()).c_str());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scoopsim: error: %s\n", OneLine(e.what()).c_str());
    return kExitFailure;
  }
  return kExitInput;  // unreachable: a subcommand is required
}

}  // namespace

int main(int argc, char** argv) { return Main(argc, argv); }

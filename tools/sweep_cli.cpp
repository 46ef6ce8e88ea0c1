#include "tools/sweep_cli.h"

#include <cstdio>
#include <filesystem>
#include <map>

#include "sim/studies/commands.h"
#include "sim/input/scene.h"
#include "tools/cli_checks.h"

namespace tools {

void SweepCommands::AddTo(CLI::App* app) {
  sweep_ = app->add_subcommand(
      "sweep",
      "Run (or resume) a sweep's cases: plainly one after another, under mpirun handed out to "
      "the ranks, or one case with --case; DIR/cases/<name>.h5 each, then DIR/table.h5");
  sweep_->add_option("SWEEP", sweep_file_, "Sweep file (YAML), e.g. scenes/sweeps/tiny.yaml")
      ->required();
  sweep_->add_option("-o,--output", sweep_options_.dir, "Output folder")->capture_default_str();
  sweep_
      ->add_option("--case", sweep_options_.only_case,
                   "Run only case I (0-based, the order of --list): one task of a job array")
      ->check(WholeNonNegative());
  threads_ = sweep_
                 ->add_option("--threads", sweep_options_.threads,
                              "DEM threads per case; 0 = all cores (default: the scene's "
                              "`threads` when plain, 1 per rank under mpirun)")
                 ->check(CLI::Range(0, 4096));
  sweep_
      ->add_option("--checkpoint-every", sweep_options_.checkpoint_every,
                   "Keep a running case's state (its pour so far, or its pass) in "
                   "DIR/cases/<name>.parts/ every this many seconds of wall time and when "
                   "stopped, so that the same command goes on from there bit for bit; 0 = never "
                   "(a stopped case then restarts its pass, or its pour)")
      ->capture_default_str()
      ->check(FiniteNonNegative("s"));
  sweep_->add_flag("--list", list_,
                   "Print the cases (index, name, settings, cost, where each stands in the output "
                   "folder) and exit");
  sweep_->add_flag("--no-table", no_table_, "Do not build DIR/table.h5 at the end");
  sweep_->add_flag("-q,--quiet", sweep_options_.quiet, "No progress line within a case");

  CLI::App* table = app->add_subcommand("table", "The wrench lookup table");
  table->require_subcommand(1);
  build_ =
      table->add_subcommand("build", "Build the table from a sweep's case files (DIR/cases/*.h5)");
  build_->add_option("DIR", build_dir_, "The sweep's output folder")->required();
  build_->add_option("-o,--output", build_output_, "Table file (HDF5)")->capture_default_str();
  build_->add_option("--rho-step-mm", build_options_.rho_step_mm, "rho grid step [mm]")
      ->capture_default_str()
      ->check(FinitePositive("mm"));
  build_->add_option("--rho-max-mm", build_options_.rho_max_mm, "rho grid end [mm]")
      ->capture_default_str()
      ->check(FiniteNonNegative("mm"));
  build_
      ->add_option("--rho", build_options_.rho,
                   "What rho measures from first contact: path (the length of the CoM's path, "
                   "the study's and the lander's) or along (the CoM's displacement along the "
                   "trench)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, sim::RhoDefinition>{
          {"path", sim::RhoDefinition::kPath}, {"along", sim::RhoDefinition::kAlong}}))
      ->default_str("path");

  query_ = table->add_subcommand(
      "query", "The wrench [Fx Fy Fz Tx Ty Tz] at one point (linear in bite depth and rho)");
  query_->add_option("TABLE", query_table_, "Table file (HDF5)")->required();
  query_->add_option("--material", query_material_, "Material name, e.g. snow")->required();
  // Depth and rho in metres (as scenes and the CSV have them) or millimetres: one of each.
  query_depth_m_opt_ =
      query_->add_option("--bite-depth", query_bite_depth_, "Bite depth [m] (or --bite-depth-mm)");
  query_depth_mm_opt_ =
      query_->add_option("--bite-depth-mm", query_bite_depth_mm_, "Bite depth [mm]");
  query_->add_option("--pass", query_pass_, "Pass (1-based)")->required();
  query_rho_m_opt_ = query_->add_option(
      "--rho", query_rho_,
      "Distance since first contact [m], as the table measures it (its rho_definition: path or "
      "along) (or --rho-mm)");
  query_rho_mm_opt_ =
      query_->add_option("--rho-mm", query_rho_mm_, "Distance since first contact [mm]");
  query_->add_flag("--clamp", query_clamp_,
                   "Clamp bite depth and rho into the table's range instead of failing");
  query_->add_option("--frame", query_frame_, "scoop (l_scoop, the lander's) or body (the study's)")
      ->capture_default_str()
      ->check(CLI::IsMember({"scoop", "body"}));

  export_ = table->add_subcommand("export-csv",
                                  "Write the lander simulator's CSV: m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz");
  export_->add_option("TABLE", export_table_, "Table file (HDF5)")->required();
  export_->add_option("-o,--output", export_output_, "CSV file")->capture_default_str();
  export_
      ->add_option("--digits", export_digits_,
                   "Significant digits of the wrench (default: as many as read back to the "
                   "table's double exactly)")
      ->check(CLI::Range(1, 17));
}

namespace {

namespace fs = std::filesystem;

// An output file's path must not name a folder (one line, exit 2, instead of a filesystem error).
void RefuseFolder(const std::string& option, const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw sim::InputError(option + " " + path + ": expected a file to write, got a folder");
}

}  // namespace

int SweepCommands::Run() {
  if (*sweep_) {
    std::error_code ec;
    if (fs::exists(sweep_options_.dir, ec) && !fs::is_directory(sweep_options_.dir, ec)) {
      throw sim::InputError("-o " + sweep_options_.dir +
                            ": expected the sweep's output folder, got a file");
    }
    const sim::Sweep sweep = sim::LoadSweep(sweep_file_);
    if (list_) {
      std::fputs(sim::SweepCaseList(sweep, sweep_options_.dir).c_str(), stdout);
      return 0;
    }
    sim::SweepOptions options = sweep_options_;
    if (threads_->count() == 0) options.threads = -1;
    options.build_table = !no_table_;
    return sim::RunSweep(sweep, options);
  }
  if (*build_) {
    const std::string summary = sim::BuildWrenchTable(build_dir_, build_output_, build_options_);
    std::fprintf(stderr, "scoopsim: wrote %s: %s\n", build_output_.c_str(), summary.c_str());
    return 0;
  }
  if (*query_) {
    // One of --bite-depth [m] / --bite-depth-mm and one of --rho [m] / --rho-mm.
    const auto in_mm = [](CLI::Option* metres, CLI::Option* mm, double m_value, double* mm_value) {
      if (metres->count() > 0 && mm->count() > 0) {
        throw sim::InputError(metres->get_name() + " and " + mm->get_name() +
                              ": expected one of them (metres or millimetres), got both");
      }
      if (metres->count() == 0 && mm->count() == 0) {
        throw sim::InputError(metres->get_name() + ": expected " + metres->get_name() + " [m] or " +
                              mm->get_name() + " [mm], got neither");
      }
      if (metres->count() > 0) *mm_value = 1e3 * m_value;
    };
    in_mm(query_depth_m_opt_, query_depth_mm_opt_, query_bite_depth_, &query_bite_depth_mm_);
    in_mm(query_rho_m_opt_, query_rho_mm_opt_, query_rho_, &query_rho_mm_);
    const sim::WrenchTable table(query_table_);
    const auto frame =
        query_frame_ == "body" ? sim::WrenchTable::Frame::kBody : sim::WrenchTable::Frame::kScoop;
    const std::array<double, 6> w = table.Query(query_material_, query_bite_depth_mm_, query_pass_,
                                                query_rho_mm_, query_clamp_, frame);
    std::printf("{\"frame\":\"%s\",\"F\":[%.17g,%.17g,%.17g],\"T\":[%.17g,%.17g,%.17g]}\n",
                query_frame_ == "body" ? "body" : "l_scoop", w[0], w[1], w[2], w[3], w[4], w[5]);
    return 0;
  }
  if (*export_) {
    RefuseFolder("-o", export_output_);
    sim::RefuseOutputOverInput(export_output_, export_table_, "TABLE");
    const sim::WrenchTable table(export_table_);
    table.ExportCsv(export_output_, export_digits_);
    std::fprintf(stderr, "scoopsim: wrote %s\n", export_output_.c_str());
    return 0;
  }
  return -1;
}

}  // namespace tools

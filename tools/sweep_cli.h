// The `sweep` and `table` commands of the CLI (sim/studies/sweep.h, sim/files/wrench_table.h):
//   scoopsim sweep SWEEP.yaml [-o DIR] [--case I] [--list] [--threads N] [--no-table] [-q]
//   scoopsim table build DIR [-o TABLE.h5] [--rho-step-mm S] [--rho-max-mm R]
//   scoopsim table query TABLE.h5 --material M --bite-depth-mm D --pass P --rho-mm R
//                        [--clamp] [--frame scoop|body]
//   scoopsim table export-csv TABLE.h5 [-o table.csv]
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "sim/studies/sweep.h"
#include "sim/files/wrench_table.h"

namespace tools {

class SweepCommands {
 public:
  // Adds the commands to `app`.
  void AddTo(CLI::App* app);
  // Runs the one that was given and returns its exit status; -1 when none of them was. Bad input
  // throws sim::InputError (the caller prints it and exits 2).
  int Run();

 private:
  CLI::App* sweep_ = nullptr;
  std::string sweep_file_;
  sim::SweepOptions sweep_options_;
  CLI::Option* threads_ = nullptr;
  bool list_ = false;
  bool no_table_ = false;

  CLI::App* build_ = nullptr;
  std::string build_dir_, build_output_ = "out/table.h5";
  sim::WrenchTableOptions build_options_;

  CLI::App* query_ = nullptr;
  std::string query_table_, query_material_, query_frame_ = "scoop";
  double query_bite_depth_mm_ = 0, query_rho_mm_ = 0;  // --bite-depth-mm, --rho-mm [mm]
  double query_bite_depth_ = 0, query_rho_ = 0;        // --bite-depth, --rho [m]
  CLI::Option *query_depth_mm_opt_ = nullptr, *query_depth_m_opt_ = nullptr;
  CLI::Option *query_rho_mm_opt_ = nullptr, *query_rho_m_opt_ = nullptr;
  int query_pass_ = 0;
  bool query_clamp_ = false;

  CLI::App* export_ = nullptr;
  std::string export_table_, export_output_ = "out/table.csv";
  int export_digits_ = 0;  // 0: shortest round-trip text
};

}  // namespace tools

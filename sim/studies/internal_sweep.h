// Internal to sim/ (not a public header): the pieces of a sweep (sim/studies/sweep.h) that the plain
// runner (sweep.cpp) and the MPI one (sweep_mpi.cpp) share.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "sim/studies/sweep.h"

namespace sim::sweep {

// What running one case came to.
struct CaseOutcome {
  int exit_status = 0;   // sim::ExitStatus
  bool skipped = false;  // already done: nothing ran
  bool held = false;     // another process holds its lock (runs it): left to that process,
                         // not a failure (with --case that is a failure instead: exit_status)
  double wall = 0;       // [s] of this attempt
  int first_pass = 1;    // the pass this attempt began with (> 1: resumed)
};

// Runs (or resumes, or skips) one case into options.dir with `threads` DEM threads. Never throws:
// errors become exit statuses and the case's status record says why.
CaseOutcome RunCase(const Sweep& sweep, const SweepCase& c, const SweepOptions& options,
                    int threads);

// Whether the case is done already (status record "done" for this scene text and its file).
bool CaseDone(const SweepCase& c, const std::string& dir);

// The per-case lines of a sweep: a line when a case starts and one when it ends, with its wall
// time and the sweep's ETA (the estimated cost left at the rate of the cost finished so far in
// this session). Safe to call from several threads.
class Log {
 public:
  explicit Log(const Sweep& sweep);
  void Started(const SweepCase& c, int rank, int threads);
  void Finished(const SweepCase& c, int rank, const CaseOutcome& outcome);
  void Skipped(const SweepCase& c);
  void Held(const SweepCase& c);  // left to the process that holds its lock

 private:
  const Sweep& sweep_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point t0_;
  double total_ = 0, done_cost_ = 0, skipped_cost_ = 0;
  int finished_ = 0;
  int failed_ = 0;  // of finished_, those that failed
};

// Under a launcher (Open MPI's OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK in the environment).
bool LaunchedByMpi();
// The MPI sweep: returns this rank's exit status.
int RunMpi(const Sweep& sweep, const SweepOptions& options);
// When every case is done: builds DIR/table.h5 (SweepOptions::build_table), then calls
// SweepOptions::on_complete; returns an exit status.
int FinishTable(const Sweep& sweep, const SweepOptions& options);

}  // namespace sim::sweep

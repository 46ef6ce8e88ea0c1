// A sweep over Open MPI (sim/studies/sweep.h): rank 0 hands the cases out, longest first (estimated
// cost: particles x planned simulated time), one at a time to whichever rank asks; ranks 1..N-1
// run what they are given, and so does rank 0 on a second thread, so N ranks run N cases at a
// time. Only rank 0's main thread calls MPI (MPI_THREAD_FUNNELED). Every rank runs a case with
// its own World on `threads` threads (1 unless --threads says otherwise): a case's output is the
// same whoever runs it. At the end rank 0 builds DIR/table.h5.
//
// Messages: a worker sends kTagReport {case index or -1, exit status, wall, 1 skipped / 2 held by
// another process / 0} (its last case's outcome; -1 for none) and receives kTagAssign {case index,
// or -1: no more work}.
#include <mpi.h>

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <thread>

#include "sim/input/exit_status.h"
#include "sim/files/h5_output.h"
#include "sim/studies/internal_sweep.h"
#include "sim/loop/progress.h"

namespace sim::sweep {
namespace {

constexpr int kTagReport = 1;
constexpr int kTagAssign = 2;

// The cases still to hand out, longest first (ties in sweep order).
std::deque<int> Queue(const Sweep& sweep, const std::string& dir, Log* log) {
  std::vector<int> order;
  for (const SweepCase& c : sweep.cases) {
    if (CaseDone(c, dir)) {
      log->Skipped(c);
    } else {
      order.push_back(c.index);
    }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return sweep.cases[a].estimate > sweep.cases[b].estimate; });
  return {order.begin(), order.end()};
}

int Worker(const Sweep& sweep, const SweepOptions& options, int rank, int threads) {
  double report[4] = {-1, 0, 0, 0};
  int exit_status = kExitOk;
  for (;;) {
    MPI_Send(report, 4, MPI_DOUBLE, 0, kTagReport, MPI_COMM_WORLD);
    int index = -1;
    MPI_Recv(&index, 1, MPI_INT, 0, kTagAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (index < 0) break;
    const CaseOutcome outcome = RunCase(sweep, sweep.cases[index], options, threads);
    report[0] = index;
    report[1] = outcome.exit_status;
    report[2] = outcome.wall;
    report[3] = outcome.skipped ? 1 : (outcome.held ? 2 : 0);
    if (outcome.exit_status != kExitOk && exit_status == kExitOk) exit_status = outcome.exit_status;
  }
  (void)rank;
  return exit_status;
}

// Rank 0: the dispatcher on the main thread, a worker on a second one.
int Dispatcher(const Sweep& sweep, const SweepOptions& options, int ranks, int threads) {
  Log log(sweep);
  std::deque<int> queue = Queue(sweep, options.dir, &log);
  int exit_status = kExitOk;
  const auto note = [&](const SweepCase& c, int rank, const CaseOutcome& outcome) {
    if (outcome.held) {
      log.Held(c);
    } else if (outcome.skipped) {
      log.Skipped(c);
    } else {
      log.Finished(c, rank, outcome);
    }
    if (outcome.exit_status != kExitOk && exit_status == kExitOk) exit_status = outcome.exit_status;
  };
  // Hands out the next case (-1: none left, or stopping).
  const auto next = [&](int rank) {
    if (StopRequested() || queue.empty()) return -1;
    const int index = queue.front();
    queue.pop_front();
    log.Started(sweep.cases[index], rank, threads);
    return index;
  };

  // The local worker takes cases through `local_case` and hands outcomes back.
  std::mutex mutex;
  std::condition_variable wake;
  int local_case = -2;  // -2: waiting for one, -1: no more, >= 0: that case
  bool local_reported = false;
  int local_done_index = -1;
  CaseOutcome local_outcome;
  std::thread local([&] {
    for (;;) {
      int index;
      {
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait(lock, [&] { return local_case != -2; });
        index = local_case;
        if (index < 0) return;
      }
      const CaseOutcome outcome = RunCase(sweep, sweep.cases[index], options, threads);
      std::lock_guard<std::mutex> lock(mutex);
      local_outcome = outcome;
      local_done_index = index;
      local_reported = true;
      local_case = -2;
    }
  });
  {
    std::lock_guard<std::mutex> lock(mutex);
    local_case = next(0);
  }
  wake.notify_one();
  bool local_active = true;
  {
    std::lock_guard<std::mutex> lock(mutex);
    local_active = local_case >= 0;
  }

  int remote_active = ranks - 1;
  while (remote_active > 0 || local_active) {
    bool busy = false;
    // A worker rank reports and asks.
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagReport, MPI_COMM_WORLD, &flag, &status);
    if (flag) {
      busy = true;
      double report[4];
      MPI_Recv(report, 4, MPI_DOUBLE, status.MPI_SOURCE, kTagReport, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
      if (report[0] >= 0) {
        CaseOutcome outcome;
        outcome.exit_status = static_cast<int>(report[1]);
        outcome.wall = report[2];
        outcome.skipped = report[3] == 1;
        outcome.held = report[3] == 2;
        note(sweep.cases[static_cast<int>(report[0])], status.MPI_SOURCE, outcome);
      }
      int index = next(status.MPI_SOURCE);
      MPI_Send(&index, 1, MPI_INT, status.MPI_SOURCE, kTagAssign, MPI_COMM_WORLD);
      if (index < 0) --remote_active;
    }
    // The local worker finished one.
    if (local_active) {
      std::unique_lock<std::mutex> lock(mutex);
      if (local_reported) {
        busy = true;
        local_reported = false;
        note(sweep.cases[local_done_index], 0, local_outcome);
        local_case = next(0);
        local_active = local_case >= 0;
        lock.unlock();
        wake.notify_one();
      }
    }
    if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    local_case = -1;
  }
  wake.notify_one();
  local.join();
  if (StopRequested() && exit_status == kExitOk) exit_status = kExitStopped;
  if (exit_status != kExitOk) return exit_status;
  return FinishTable(sweep, options);
}

}  // namespace

bool LaunchedByMpi() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMI_SIZE") != nullptr ||
         std::getenv("PMIX_RANK") != nullptr;
}

int RunMpi(const Sweep& sweep, const SweepOptions& options) {
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const int threads = options.threads >= 0 ? options.threads : 1;
  int exit_status = kExitOk;
  try {
    if (rank == 0) {
      Status("scoopsim: sweep: %zu cases on %d MPI ranks (%d thread%s each)\n", sweep.cases.size(),
             ranks, threads, threads == 1 ? "" : "s");
      exit_status = Dispatcher(sweep, options, ranks, threads);
    } else {
      exit_status = Worker(sweep, options, rank, threads);
    }
  } catch (const std::exception& e) {
    // RunCase does not throw; the table build may (rank 0, after every worker is done).
    Status("scoopsim: sweep: rank %d: %s\n", rank, e.what());
    exit_status = dynamic_cast<const InputError*>(&e) ? kExitInput : kExitFailure;
  }
  MPI_Finalize();
  return exit_status;
}

}  // namespace sim::sweep

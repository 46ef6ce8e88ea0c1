// The process exit statuses of every scoopsim command, in one place.
#pragma once

namespace sim {

enum ExitStatus : int {
  kExitOk = 0,
  kExitFailure = 1,      // an unexpected error (a bug or the system: disk, memory)
  kExitInput = 2,        // bad input (scene, mesh, bed file, CLI); one line says what and where
  kExitUnstable = 3,     // the simulation went unstable; the diagnostic names particle and knob
  kExitNotSettled = 4,   // the bed did not settle within bed.settle.max_time (saved all the same)
  kExitStopped = 130,    // SIGINT/SIGTERM: outputs closed cleanly
};

}  // namespace sim

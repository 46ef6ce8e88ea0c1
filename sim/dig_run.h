// The dig run: the scoop mesh follows the trajectory pass after pass through the bed; the
// wrench on it is recorded under /scoop/ and the sample it holds is removed after each pass.
#pragma once

#include "dem/system.h"
#include "sim/h5_output.h"
#include "sim/runner.h"
#include "sim/scene.h"

namespace sim {

// Runs every pass of scene.dig on `system` (a settled bed), writing /scoop/ and /series/ rows
// to `out`. Returns an exit status (0, 3 unstable, 130 stopped).
int RunDig(const Scene& scene, const RunOptions& options, dem::System* system, H5Output* out);

}  // namespace sim

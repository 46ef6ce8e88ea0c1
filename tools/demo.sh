#!/usr/bin/env bash
# The demo: installs the dependencies, builds scoopsim, and runs the quick dig
# (scenes/quick_dig.yaml): a bed of 1700 coarse snow spheres is poured and settled, then the
# simplified Phoenix scoop digs one pass on the paper's Table 1 trajectory. Writes the run
# (HDF5 + XDMF sidecar for ParaView), rendered frames and a plot of the wrench against rho.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh

# Tests stay on (SCOOPSIM_TESTS, the default): build/ is also tools/test.sh's, and install-deps.sh
# has installed GoogleTest; only the CLI is built.
cmake --preset release >/dev/null
cmake --build build -j"$(nproc)" --target scoopsim

mkdir -p out
build/scoopsim run scenes/quick_dig.yaml -o out/quick_dig.h5 --frames out/quick_dig_frames
# The Python the Debian packages above went into (a python3 earlier on PATH may lack them).
"${SCOOPSIM_PYTHON:-/usr/bin/python3}" tools/plot_wrench.py out/quick_dig.h5 -o out/quick_dig_wrench.png

echo
echo "demo: outputs"
echo "  out/quick_dig.h5           /scoop/ wrench (body, l_scoop and world frames), pose, rho, collected"
echo "                             mass; /series/; particle snapshots; the scene and provenance (HDF5)"
echo "  out/quick_dig.xdmf         open it in ParaView (XDMF3 reader) to play the particle snapshots"
echo "  out/quick_dig_wrench.png   |F|, |T| and the six components against rho (tools/plot_wrench.py)"
echo "  out/quick_dig_frames/      frame_NNNNNN.png, 20 frames a simulated second (OSMesa, 1280x720)"

#!/usr/bin/env bash
# The demo: installs the dependencies, builds scoopsim, pours and settles 8000 snow spheres in a
# small box and runs 0.05 s of it (scenes/default.yaml), writing HDF5 + an XDMF sidecar for ParaView.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh

cmake --preset release >/dev/null
cmake --build build -j"$(nproc)" --target scoopsim

# Idle OpenMP threads sleep instead of spinning: on a busy machine spinning barriers slow the
# run down tens of times.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"
mkdir -p out
build/scoopsim run scenes/default.yaml -o out/default.h5

echo
echo "demo: outputs"
echo "  out/default.h5  time series, particle snapshots, the scene and provenance (HDF5)"
for sidecar in out/default*.xdmf; do
  if [ -e "$sidecar" ]; then
    echo "  $sidecar  open it in ParaView (XDMF3 reader) to play the particle snapshots"
  fi
done

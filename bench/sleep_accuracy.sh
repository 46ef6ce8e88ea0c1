#!/usr/bin/env bash
# What sleeping costs in accuracy and buys in speed (the dig issue's 2% criterion): runs a dig
# scene with sleeping on and off and compares peak and mean |F| on the scoop and the wall time.
#   bench/sleep_accuracy.sh [SCENE] [THREADS]      (default scenes/quick_dig.yaml, 2)
#   KEEP=DIR bench/sleep_accuracy.sh ...           keeps the bed and both runs in DIR
# Besides the run's own line it prints, from the run file (after first contact, rho > 0), the
# peak of |F|, the peak of |F| smoothed by the plot's centred 25-sample moving average
# (tools/plot_wrench.py), and the mean of |F|.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/quick_dig.yaml}
threads=${2:-2}
if [ -n "${KEEP:-}" ]; then
  work=$KEEP
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi
# The bed once, so both runs start from the same state.
build/scoopsim bed "$scene" -o "$work/bed.h5" --threads "$threads" -q
for mode in true false; do
  # Only the switch changes: the scene's other sleep keys (wake zone, quiet speed) stay.
  sed -e "/^sleep:/s|enabled: *[a-z]*|enabled: $mode|" \
      -e "s|^\(  *\)count: \(.*\)|&\n\1file: $work/bed.h5|" "$scene" > "$work/scene_$mode.yaml"
  sed -i "s|mesh: \.\./assets|mesh: $PWD/assets|; s|^materials: materials.yaml|materials: $PWD/scenes/materials.yaml|" \
      "$work/scene_$mode.yaml"
  start=$(date +%s.%N)
  build/scoopsim run "$work/scene_$mode.yaml" -o "$work/run_$mode.h5" --threads "$threads" -q \
      2> "$work/log_$mode.txt"
  end=$(date +%s.%N)
  line=$(grep "scoopsim: dig:" "$work/log_$mode.txt")
  echo "sleep=$mode wall_s=$(awk "BEGIN{printf \"%.1f\", $end - $start}") $line"
  /usr/bin/python3 - "$work/run_$mode.h5" <<'PY'
import sys
import h5py
import numpy as np
sys.path.insert(0, "tools")
from plot_wrench import smooth
with h5py.File(sys.argv[1], "r") as f:
    rho = f["scoop/rho"][:]
    F = np.linalg.norm(f["scoop/force_body"][:], axis=1)
m = rho > 0
print(f"  |F| after first contact: peak {F[m].max():.4f} N, peak smoothed (25) "
      f"{smooth(F, 25)[m].max():.4f} N, mean {F[m].mean():.4f} N")
PY
done

#!/bin/bash
# The sand testbed (paper section 4, Fig. 12-13) over several beds, and its plot:
#   tools/testbed_sand.sh [OUT_DIR]        (default out/testbed; needs build/scoopsim)
# 1. scenes/paper/testbed_sand.yaml on its own bed (seed 1) under `scoopsim study balovnev`: the
#    dig and Balovnev's model along it (OUT/seed1.h5, .balovnev.csv, .balovnev.png, the table);
# 2. the same dig on beds of seeds 2-5 (scenes/sweeps/testbed_sand.yaml: OUT/sweep/cases/*.h5);
# 3. tools/plot_testbed.py: the three body-frame force components against the distance pushed,
#    each bed, their mean and 95% band (OUT/testbed_sand.png) and the summary (OUT/summary.csv).
# One DEM thread a run (THREADS=N to change); CPU and wall times in OUT/times.txt. A run already
# done is kept (the sweep skips its finished cases; seed1.h5 is made again only when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/testbed}
threads=${THREADS:-1}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
mkdir -p "$out"
timed() {  # timed LABEL COMMAND...: runs it, appends "LABEL user+sys wall" to OUT/times.txt
  local label=$1
  shift
  local t0 t1
  t0=$(date +%s.%N)
  /usr/bin/time -f "%U %S" -o "$out/.time" "$@"
  t1=$(date +%s.%N)
  read -r user sys < "$out/.time"
  awk -v l="$label" -v u="$user" -v s="$sys" -v a="$t0" -v b="$t1" \
    'BEGIN { printf "%s cpu_s %.1f wall_s %.1f\n", l, u + s, b - a }' >> "$out/times.txt"
}
if [ ! -f "$out/seed1.h5" ]; then
  timed seed1 build/scoopsim study balovnev scenes/paper/testbed_sand.yaml -o "$out/seed1.h5" \
    --threads "$threads" -q | tee "$out/balovnev_table.md"
fi
timed sweep build/scoopsim sweep scenes/sweeps/testbed_sand.yaml -o "$out/sweep" --no-table \
  --threads "$threads" -q
"${SCOOPSIM_PYTHON:-python3}" tools/plot_testbed.py "$out/seed1.h5" "$out"/sweep/cases/*.h5 \
  -o "$out/testbed_sand.png" --csv "$out/summary.csv"
echo "tools/testbed_sand.sh: $out/testbed_sand.png, $out/seed1.balovnev.png, $out/times.txt"

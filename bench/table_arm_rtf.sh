#!/usr/bin/env bash
# The table-driven arm's real-time factor (issue 20 item 4): scenes/arm/table_snow.yaml, a
# five-pass dig of the arm with its scoop wrench from a wrench table (no DEM), on one core,
# NRUNS times. Prints each run's line and appends one CSV row per run to
# bench/results/$MACHINE/table_arm_rtf.csv: simulated and wall seconds, the real-time factor on
# the wall clock and on the process's CPU time (user + sys: what an idle core would give), the
# Bullet steps and the load average when the run started (the host is shared).
#
#   bench/table_arm_rtf.sh                         3 runs, 1 thread
#   NRUNS=1 bench/table_arm_rtf.sh
#
# Environment: NRUNS (3), BIN (build/scoopsim), MACHINE (vm), SCENE (scenes/arm/table_snow.yaml;
# e.g. a copy of an older version for an older BIN), COMMIT (the CSV's commit column: the
# checkout's HEAD), NO_SNAPSHOTS (default `--set output.snapshot_every=0`: the arm alone, as before
# the scene wrote snapshots, which cost about a third of its wall time; empty for a BIN older than
# --set). The table is built once, when out/table_arm_bench/table.h5 is missing
# (scenes/sweeps/table_arm_bench.yaml, ~2 minutes).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
NRUNS=${NRUNS:-3}
BIN=${BIN:-$ROOT/build/scoopsim}
MACHINE=${MACHINE:-vm}
NO_SNAPSHOTS=${NO_SNAPSHOTS---set output.snapshot_every=0}
SCENE=${SCENE:-$ROOT/scenes/arm/table_snow.yaml}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/table_arm_rtf.csv"
mkdir -p "$RESDIR"
[ -s "$CSV" ] || echo "date,commit,scene,run,threads,load1,simulated_s,wall_s,cpu_s,rtf_wall,rtf_cpu,bullet_steps" >"$CSV"
if [ ! -s "$ROOT/out/table_arm_bench/table.h5" ]; then
  "$BIN" sweep "$ROOT/scenes/sweeps/table_arm_bench.yaml" -o "$ROOT/out/table_arm_bench" \
    --threads 1 --quiet
fi
commit=${COMMIT:-$(git -C "$ROOT" rev-parse --short HEAD)}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for run in $(seq 1 "$NRUNS"); do
  load1=$(cut -d' ' -f1 /proc/loadavg)
  /usr/bin/time -f "%U %S" -o "$work/time" "$BIN" run "$SCENE" -o "$work/out.h5" --threads 1 \
    --quiet $NO_SNAPSHOTS 2>"$work/log" || { cat "$work/log"; exit 1; }
  line=$(grep "table-driven arm:" "$work/log")
  echo "run $run (load $load1): ${line#scoopsim: }"
  /usr/bin/python3 - "$line" "$(cat "$work/time")" "$run" "$load1" "$commit" "$CSV" \
    "${SCENE#"$ROOT"/}" <<'PY'
import datetime, re, sys
line, cpu, run, load1, commit, csv, scene = sys.argv[1:]
m = re.search(r"([\d.e+]+) s simulated in ([\d.e+]+) s wall: ([\d.e+]+) x real time \((\d+) Bullet", line)
simulated, wall, rtf, steps = float(m[1]), float(m[2]), float(m[3]), int(m[4])
cpu_s = sum(float(x) for x in cpu.split())
with open(csv, "a") as f:
    f.write(f"{datetime.date.today()},{commit},{scene},{run},1,{load1},"
            f"{simulated:.4g},{wall:.4g},{cpu_s:.4g},{rtf:.3g},{simulated / cpu_s:.3g},{steps}\n")
print(f"  cpu {cpu_s:.1f} s: {simulated / cpu_s:.3g} x real time per CPU second")
PY
done
echo "appended to $CSV"

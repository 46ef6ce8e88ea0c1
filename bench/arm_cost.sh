#!/usr/bin/env bash
# The coupling's cost: the same dig with the scoop on the arm (Bullet, coupled every step) and on
# its prescribed path (KinematicDriver), as interleaved runs (kinematic, coupled, kinematic, ...)
# from one saved bed, so that a shared host's slow spells hit both alike. Prints each run's dig
# wall time (simulated / the printed real-time factor: 3 digits; the thread count held fixed, since
# the governor's probes of fewer threads would differ between runs) and the run's CPU time (user +
# sys, bed load included: the same for both), the medians, their ratios (coupled / kinematic)
# and the coupled dig's real-time factor (simulated / wall); appends one CSV row per run to
# bench/results/$MACHINE/arm_cost.csv.
#
#   bench/arm_cost.sh                              scenes/arm/nominal_snow.yaml, 5 pairs, 1 thread
#   SCENE=scenes/fault/boulder.yaml NRUNS=3 THREADS=2 bench/arm_cost.sh
#
# Environment: SCENE (a scene with an arm: block), NRUNS (5), THREADS (1), BIN (build/scoopsim),
# MACHINE (hostname), LABEL (appended to the CSV's scene column as scene@LABEL, e.g. the binary's
# commit when two binaries are compared).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SCENE=${SCENE:-$ROOT/scenes/arm/nominal_snow.yaml}
NRUNS=${NRUNS:-5}
THREADS=${THREADS:-1}
BIN=${BIN:-$ROOT/build/scoopsim}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/arm_cost.csv"
mkdir -p "$RESDIR"
[ -s "$CSV" ] || echo "date,scene,driver,run,threads,dig_wall_s,simulated_s,run_cpu_s" >"$CSV"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# One bed for both; the two scenes are the scene with bed.file set, with and without its arm.
"$BIN" bed "$SCENE" -o "$work/bed.h5" --threads "$THREADS" --quiet 2>/dev/null || [ $? -eq 4 ]
/usr/bin/python3 - "$SCENE" "$work" <<'PY'
import os, re, sys
scene, work = sys.argv[1:]
text = open(scene).read()
folder = os.path.dirname(os.path.abspath(scene))
# Relative file names of the scene resolved against its own folder.
text = re.sub(r"(materials: |mesh: |urdf: )(\.\./[^\s,}]+)",
              lambda m: m.group(1) + os.path.normpath(os.path.join(folder, m.group(2))), text)
text = re.sub(r"\nbed:\n", "\nbed:\n  file: " + work + "/bed.h5\n", text)
coupled = text
if "urdf:" not in coupled:
    coupled = coupled.replace("\narm:\n", "\narm:\n  urdf: " +
                              os.path.normpath(os.path.join(folder, "../../assets/lander_arm.urdf")) + "\n")
kinematic = re.sub(r"\narm:\n(  .*\n)+", "\n", text)
open(work + "/coupled.yaml", "w").write(coupled)
open(work + "/kinematic.yaml", "w").write(kinematic)
PY

TIMEFORMAT='%U %S'  # bash's `time`: the run's user and system CPU seconds
for r in $(seq "$NRUNS"); do
  for d in kinematic coupled; do
    { time "$BIN" run "$work/$d.yaml" -o "$work/$d.h5" --threads "$THREADS" --fixed-threads --quiet \
      2>"$work/err" >/dev/null; } 2>"$work/cpu"
    sim=$(sed -n 's/^scoopsim: dig: .* steps, \([0-9.e+-]*\) s simulated.*/\1/p' "$work/err")
    rtf=$(sed -n 's/^scoopsim: dig: [0-9.]* s wall (\([0-9.e+-]*\) x real time.*/\1/p' "$work/err")
    wall=$(awk -v s="$sim" -v f="$rtf" 'BEGIN{printf "%.4g", s / f}')
    cpu=$(awk '{printf "%.4g", $1 + $2}' "$work/cpu")
    echo "$d run $r: dig wall $wall s, $sim s simulated, run CPU $cpu s"
    echo "$(date -u +%FT%T),$(basename "$SCENE")${LABEL:+@$LABEL},$d,$r,$THREADS,$wall,$sim,$cpu" >>"$CSV"
  done
done | tee "$work/log"
/usr/bin/python3 - "$work/log" <<'PY'
import re, statistics, sys
runs = {"kinematic": [], "coupled": []}
cpus = {"kinematic": [], "coupled": []}
sim = 0
for line in open(sys.argv[1]):
    m = re.match(r"(\w+) run \d+: dig wall ([0-9.e+-]+) s, ([0-9.e+-]+) s simulated, run CPU "
                 r"([0-9.e+-]+) s", line)
    if m:
        runs[m.group(1)].append(float(m.group(2)))
        cpus[m.group(1)].append(float(m.group(4)))
        sim = float(m.group(3))
k, c = statistics.median(runs["kinematic"]), statistics.median(runs["coupled"])
kc, cc = statistics.median(cpus["kinematic"]), statistics.median(cpus["coupled"])
pairs = sorted(b / a for a, b in zip(runs["kinematic"], runs["coupled"]))
print(f"kinematic median {k:.3f} s [{min(runs['kinematic']):.3f}, {max(runs['kinematic']):.3f}], "
      f"coupled median {c:.3f} s [{min(runs['coupled']):.3f}, {max(runs['coupled']):.3f}]")
print(f"coupled / kinematic = {c / k:.3f} (pairs: median {statistics.median(pairs):.3f}, "
      f"[{pairs[0]:.3f}, {pairs[-1]:.3f}]); run CPU {cc:.2f} / {kc:.2f} s = {cc / kc:.3f}; "
      f"coupled real-time factor = {sim / c:.3f} ({sim:.3g} s simulated)")
PY

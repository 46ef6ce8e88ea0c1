#!/usr/bin/env bash
# The k-substep study (issue 19): the coupled dig of a scene with one Bullet step per k DEM steps
# on their mean wrench (arm.substeps), for k = 1, 2, 5, 10, as interleaved runs (1, 2, 5, 10, 1,
# ...) from one saved bed. Reports per k the cost a DEM step (dig wall time / DEM steps, median
# of the runs) and the wrench's difference against k = 1: the RMS over 1 ms windows of
# |mean F_k - mean F_1| (and of T) over the peak window |mean F_1|, in % (as
# tests/sim/arm_driver_test.cpp measures arm vs kinematic), and the ratio of the peak windows
# |F| (a transient shows there). For scale it also prints the bed's
# noise floor: the same difference between the kinematic path and itself moved 0.5 mm along the
# trench. The wrench is the DEM's on the scoop (/scoop/force_world, torque_world about the CoM),
# rows every 0.1 ms, so that a 1 ms window holds 10 samples.
#
# arm.substeps k needs k dt <= 1e-4 s (the PID's D term), so the scene's time step is made small
# enough for k = 10: time_step.rayleigh_fraction RAYLEIGH (0.05; nominal_snow's 0.25 allows k <= 2).
#
#   bench/arm_substeps.sh                          scenes/arm/nominal_snow.yaml, 3 rounds, 1 thread
#   NRUNS=5 KS="1 2 5 10" bench/arm_substeps.sh
#   KS="1 1x 2 5 10" bench/arm_substeps.sh       a k with an x: the PID's D term explicit
#                                                (arm.d_term: explicit; plain k: the scene's)
#
# The cost is taken from the run's CPU time (user + system, bed load included: the same for every
# k), which a shared host's contention moves far less than the wall time (also recorded).
#
# Environment: SCENE, NRUNS (3), KS ("1 2 5 10"), RAYLEIGH (0.05), THREADS (1),
# BIN (build/scoopsim), MACHINE (hostname), QUIET_WAIT (seconds, default 0: bench/wait_quiet.sh),
# COMMIT (the CSV's commit column; default the checkout's HEAD).
# Appends one CSV row per run to bench/results/$MACHINE/arm_substeps.csv.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SCENE=${SCENE:-$ROOT/scenes/arm/nominal_snow.yaml}
NRUNS=${NRUNS:-3}
KS=${KS:-1 2 5 10}
RAYLEIGH=${RAYLEIGH:-0.05}
THREADS=${THREADS:-1}
BIN=${BIN:-$ROOT/build/scoopsim}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/arm_substeps.csv"
COMMIT=${COMMIT:-$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)}
mkdir -p "$RESDIR"
[ -s "$CSV" ] ||
  echo "date,commit,scene,rayleigh_fraction,k,run,threads,dig_wall_s,run_cpu_s,dem_steps,ms_per_dem_step_wall,ms_per_dem_step_cpu,force_rms_pct_of_peak,torque_rms_pct_of_peak,peak_force_ratio" >"$CSV"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The scenes: the scene at RAYLEIGH with file names made absolute and rows every 0.1 ms; one per
# k with arm.substeps k; a kinematic one (no arm:) and the same moved 0.5 mm (the noise floor).
/usr/bin/python3 - "$SCENE" "$work" "$RAYLEIGH" "$KS" <<'PY'
import os, re, sys
scene, work, rayleigh, ks = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split()
text = open(scene).read()
folder = os.path.dirname(os.path.abspath(scene))
text = re.sub(r"(materials: |mesh: |urdf: )(\.\./[^\s,}]+)",
              lambda m: m.group(1) + os.path.normpath(os.path.join(folder, m.group(2))), text)
text, n = re.subn(r"rayleigh_fraction: [0-9.eE+-]+", "rayleigh_fraction: " + rayleigh, text)
assert n == 1, "the scene needs time_step: {rayleigh_fraction: ...}"
text, n = re.subn(r"\n  interval: [0-9.eE+-]+", "\n  interval: 1.0e-4", text)
assert n == 1, "the scene needs dig.interval"
open(work + "/bed.yaml", "w").write(text)
text = re.sub(r"\nbed:\n", "\nbed:\n  file: " + work + "/bed.h5\n", text)
assert "\narm:\n" in text, "the scene needs an arm: block"
for k in ks:
    keys = f"  substeps: {k.rstrip('x')}\n" + ("  d_term: explicit\n" if k.endswith("x") else "")
    open(f"{work}/k{k}.yaml", "w").write(text.replace("\narm:\n", "\narm:\n" + keys))
kinematic = re.sub(r"\narm:\n(  .*\n)+", "\n", text)
open(work + "/kinematic.yaml", "w").write(kinematic)
m = re.search(r"start: \[([0-9.eE+-]+), ", kinematic)
shifted = kinematic[:m.start(1)] + repr(float(m.group(1)) + 0.5e-3) + kinematic[m.end(1):]
open(work + "/shifted.yaml", "w").write(shifted)
PY

"$BIN" bed "$work/bed.yaml" -o "$work/bed.h5" --threads "$THREADS" --quiet 2>/dev/null || [ $? -eq 4 ]
for d in kinematic shifted; do
  "$BIN" run "$work/$d.yaml" -o "$work/$d.h5" --threads "$THREADS" --quiet 2>/dev/null
done
. "$ROOT/bench/wait_quiet.sh"
TIMEFORMAT='%U %S'  # bash's `time`: the run's user and system CPU seconds
for r in $(seq "$NRUNS"); do
  for k in $KS; do
    wait_quiet
    { time "$BIN" run "$work/k$k.yaml" -o "$work/k$k.h5" --threads "$THREADS" --quiet \
      2>"$work/err" >/dev/null; } 2>"$work/cpu"
    wall=$(sed -n 's/^scoopsim: dig: \([0-9.]*\) s wall.*/\1/p' "$work/err")
    steps=$(sed -n 's/^scoopsim: dig: [0-9]* particles, \([0-9]*\) steps.*/\1/p' "$work/err")
    cpu=$(awk '{print $1 + $2}' "$work/cpu")
    echo "k $k run $r: dig wall $wall s, run CPU $cpu s, $steps DEM steps"
  done
done | tee "$work/log"

/usr/bin/python3 - "$work" "$KS" "$CSV" "$(basename "$SCENE")" "$RAYLEIGH" "$THREADS" "$COMMIT" <<'PY'
import datetime, re, statistics, sys
import h5py
import numpy as np
work, ks, csv, scene, rayleigh, threads, commit = sys.argv[1:]
ks = ks.split()

def windows(path):
    with h5py.File(path, "r") as f:
        t = f["/scoop/time"][:]
        F = f["/scoop/force_world"][:]
        T = f["/scoop/torque_world"][:]
    w = int(round(1e-3 / (t[1] - t[0])))  # rows per 1 ms window
    n = len(t) // w * w
    return F[:n].reshape(-1, w, 3).mean(axis=1), T[:n].reshape(-1, w, 3).mean(axis=1)

def rms_over_peak(a, b):  # a against the reference b
    n = min(len(a), len(b))
    return 100 * np.sqrt(np.mean(np.sum((a[:n] - b[:n]) ** 2, axis=1))) / np.max(
        np.linalg.norm(b[:n], axis=1))

ref_F, ref_T = windows(f"{work}/k{ks[0]}.h5")
kin_F, kin_T = windows(f"{work}/kinematic.h5")
sh_F, sh_T = windows(f"{work}/shifted.h5")
diff, peak = {}, {}
for k in ks:
    F, T = windows(f"{work}/k{k}.h5")
    diff[k] = (rms_over_peak(F, ref_F), rms_over_peak(T, ref_T))
    peak[k] = np.max(np.linalg.norm(F, axis=1)) / np.max(np.linalg.norm(ref_F, axis=1))
wall_ms, cpu_ms = {k: [] for k in ks}, {k: [] for k in ks}
now = datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%S")
with open(csv, "a") as out:
    for line in open(f"{work}/log"):
        m = re.match(r"k (\d+x?) run (\d+): dig wall ([0-9.]+) s, run CPU ([0-9.]+) s, (\d+) DEM",
                     line)
        if not m:
            continue
        k, r, wall, cpu, steps = (m.group(1), m.group(2), float(m.group(3)), float(m.group(4)),
                                  int(m.group(5)))
        wall_ms[k].append(1e3 * wall / steps)
        cpu_ms[k].append(1e3 * cpu / steps)
        out.write(f"{now},{commit},{scene},{rayleigh},{k},{r},{threads},{wall},{cpu},{steps},"
                  f"{wall_ms[k][-1]:.5f},{cpu_ms[k][-1]:.5f},{diff[k][0]:.2f},{diff[k][1]:.2f},"
                  f"{peak[k]:.3f}\n")
print(f"peak 1 ms |F| (k = {ks[0]}): {np.max(np.linalg.norm(ref_F, axis=1)):.3g} N, "
      f"|T|: {np.max(np.linalg.norm(ref_T, axis=1)):.3g} N m")
print("| k | ms per DEM step, CPU (median [min, max]) | wall (median) | force RMS diff % of peak "
      "| torque RMS diff % of peak | peak abs(F) / k = 1's |")
print("|---|---|---|---|---|---|")
for k in ks:
    c = cpu_ms[k]
    print(f"| {k} | {statistics.median(c):.4f} [{min(c):.4f}, {max(c):.4f}] | "
          f"{statistics.median(wall_ms[k]):.4f} | {diff[k][0]:.1f} | {diff[k][1]:.1f} | "
          f"{peak[k]:.2f} |")
print(f"noise floor (kinematic path vs itself moved 0.5 mm): force "
      f"{rms_over_peak(sh_F, kin_F):.1f} %, torque {rms_over_peak(sh_T, kin_T):.1f} %; "
      f"arm k = {ks[0]} vs kinematic: force {rms_over_peak(ref_F, kin_F):.1f} %, "
      f"torque {rms_over_peak(ref_T, kin_T):.1f} %")
PY

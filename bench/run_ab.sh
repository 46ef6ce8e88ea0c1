#!/usr/bin/env bash
# A/B of whole runs: `scoopsim run SCENE` with each binary in turn (A, B, A, B, ...), so that a
# shared host's slow spells hit both alike. Records each run's CPU time (user + sys, pour and dig
# and output), wall time and final state hash; prints the medians and the per-pair ratios of CPU
# time (A / B), and appends one CSV row per run to bench/results/$MACHINE/run_ab.csv, and the
# run's wall seconds by phase (the dig's closing line: pairs, integrate, rebuild, ...) as one row
# per phase to run_ab_phases.csv.
#
#   BINS="/tmp/base/scoopsim build/scoopsim" bench/run_ab.sh scenes/tiny_dig.yaml
#   BINS="..." NRUNS=5 THREADS=2 LABEL=isa bench/run_ab.sh scenes/quick_dig.yaml
#   BINS="..." STOP_AFTER=0.75 bench/run_ab.sh out/lookup/cases/snow_b15.parts/pass_2.h5
#
# With STOP_AFTER, the argument is a stopped run's output (OUT.h5 beside its OUT.restart.h5): each
# run goes on from a fresh copy of the two (`run --resume`) to --stop-after STOP_AFTER (seconds
# from that run's start), timing a window of a long run from its checkpoint, the reading and
# writing of the files included.
#
# Environment: BINS (required: two binaries, the baseline first), NRUNS (5), THREADS (1), LABEL
# (a word for the CSV rows), MACHINE (hostname), STOP_AFTER (none).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
: "${BINS:?set BINS to two binaries, baseline first}"
SCENE=${1:?usage: BINS=\"A B\" bench/run_ab.sh SCENE}
NRUNS=${NRUNS:-5}
THREADS=${THREADS:-1}
LABEL=${LABEL:-$(basename "$SCENE" .yaml)}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/run_ab.csv"
mkdir -p "$RESDIR"
if [ ! -s "$CSV" ]; then
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores" >"$CSV"
  echo "date,label,scene,binary,run,threads,cpu_s,wall_s,state_hash" >>"$CSV"
fi
PCSV="$RESDIR/run_ab_phases.csv"
[ -s "$PCSV" ] || echo "date,label,binary,run,phase,wall_s" >"$PCSV"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
for r in $(seq "$NRUNS"); do
  for b in $BINS; do
    out="$work/run.h5"
    if [ -n "${STOP_AFTER:-}" ]; then
      cp "$SCENE" "$out"
      cp "${SCENE%.h5}.restart.h5" "$work/run.restart.h5"
      /usr/bin/time -f "%U %S %e" -o "$work/time" "$b" run --resume "$out" --threads "$THREADS" \
        --stop-after "$STOP_AFTER" --quiet >/dev/null 2>"$work/err"
    else
      /usr/bin/time -f "%U %S %e" -o "$work/time" "$b" run "$SCENE" -o "$out" --threads "$THREADS" \
        --quiet >/dev/null 2>"$work/err"
    fi
    read -r user sys wall <"$work/time"
    hash=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1],'r').attrs['state_hash'])" "$out")
    cpu=$(awk "BEGIN{print $user + $sys}")
    echo "$b run $r: cpu $cpu s, wall $wall s, state hash $hash"
    now=$(date -u +%Y-%m-%dT%H:%M:%S)
    echo "$now,$LABEL,$SCENE,$b,$r,$THREADS,$cpu,$wall,$hash" >>"$CSV"
    # "scoopsim: dig: W s wall (...): pairs X s (P%), integrate Y s (Q%), ..."; none without a
    # dig (a plain run, a failed one): no rows, and the loop goes on
    { grep -m1 'dig: .* s wall' "$work/err" || true; } | sed 's/.*): //' | tr ',' '\n' |
      sed -n 's/^ *\([a-z]*\) \([0-9.]*\) s .*/\1,\2/p' |
      while IFS=, read -r phase sec; do echo "$now,$LABEL,$b,$r,$phase,$sec" >>"$PCSV"; done
    rm -f "$work"/run.*
  done
done
/usr/bin/python3 - "$CSV" "$LABEL" $BINS <<'PY'
import csv, statistics, sys
path, label, a, b = sys.argv[1:5]
rows = [r for r in csv.DictReader(l for l in open(path) if not l.startswith("#"))
        if r["label"] == label]
cpu = {k: [float(r["cpu_s"]) for r in rows if r["binary"] == k] for k in (a, b)}
n = min(len(cpu[a]), len(cpu[b]))
ratios = [x / y for x, y in zip(cpu[a][-n:], cpu[b][-n:])]
print(f"{label}: CPU s median {statistics.median(cpu[a]):.3g} ({a}) / {statistics.median(cpu[b]):.3g} ({b});"
      f" per pair {', '.join(f'{x:.3f}' for x in ratios)}: median {statistics.median(ratios):.3f}"
      f" ({min(ratios):.3f}-{max(ratios):.3f})")
PY
/usr/bin/python3 - "$PCSV" "$LABEL" $BINS <<'PY'
import csv, statistics, sys
path, label, a, b = sys.argv[1:5]
rows = [r for r in csv.DictReader(open(path)) if r["label"] == label]
for phase in dict.fromkeys(r["phase"] for r in rows):
    s = {k: [float(r["wall_s"]) for r in rows if r["binary"] == k and r["phase"] == phase] for k in (a, b)}
    if s[a] and s[b]:
        print(f"  {phase}: wall s median {statistics.median(s[a]):.1f} ({min(s[a]):.1f}-{max(s[a]):.1f})"
              f" / {statistics.median(s[b]):.1f} ({min(s[b]):.1f}-{max(s[b]):.1f})")
PY

#!/usr/bin/env bash
# scoopsim against LIGGGHTS 3.8 on the same settled bed, in interleaved pairs: on a shared 2-vCPU
# host the 2-thread rate of either code swings by half within an hour, so only a LIGGGHTS run and
# a scoopsim run made one right after the other compare the codes (docs/dem.md, the force pass).
#
#   bench/compare_liggghts.sh                 # 6 pairs, 2 threads / 2 MPI ranks, 50,000 particles
#   PAIRS=3 THREADS=1 bench/compare_liggghts.sh
#
# Each pair: `bench/liggghts/run_bench.sh` (one run, on scoopsim's cached bed converted) and
# `scoopsim bench settle` (the same bed, steps and thread count). Prints one line per pair and the
# medians; writes them to bench/results/$MACHINE/interleaved_<UTC date>.txt.
# Needs: build/scoopsim, liggghts and /usr/bin/time (bench/install-peers.sh), mpirun
# (openmpi-bin), /usr/bin/python3 + h5py.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PAIRS=${PAIRS:-6}
THREADS=${THREADS:-2}
PARTICLES=${PARTICLES:-50000}
STEPS=${STEPS:-2000}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
BIN="$ROOT/build/scoopsim"
BED="$ROOT/bench/cache/settle_$PARTICLES.h5"
RESDIR="$ROOT/bench/results/$MACHINE"
OUT="$RESDIR/interleaved_$(date -u +%Y-%m-%d).txt"

[ -x "$BIN" ] || { echo "compare_liggghts: $BIN not found: build first (tools/test.sh)" >&2; exit 1; }
mkdir -p "$RESDIR"
# The settled bed, made once and cached (outside the timed runs).
"$BIN" bench settle --particles "$PARTICLES" --steps 1 --threads "$THREADS" >/dev/null

rate() { /usr/bin/python3 -c 'import json, sys; print(json.loads(sys.argv[1])["particle_steps_per_s"])' "$1"; }
lines=()
for p in $(seq "$PAIRS"); do
  lig=$(MACHINE="$MACHINE" RANKS="$THREADS" NRUNS=1 NSTEPS="$STEPS" \
        "$ROOT/bench/liggghts/run_bench.sh" "$BED" | grep -v '"summary"' | tail -n 1)
  sc=$("$BIN" bench settle --particles "$PARTICLES" --steps "$STEPS" --threads "$THREADS")
  line=$(/usr/bin/python3 -c 'import sys; l, s = float(sys.argv[1]), float(sys.argv[2]); print("liggghts %.2f M  scoopsim %.2f M  ratio %.2f" % (l / 1e6, s / 1e6, s / l))' \
         "$(rate "$lig")" "$(rate "$sc")")
  echo "$line"
  lines+=("$line")
done

{
  echo "# $(date -u '+%Y-%m-%d %H:%M') UTC, $MACHINE ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) vCPUs), $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?'): $PAIRS interleaved pairs, each"
  echo "#   RANKS=$THREADS NRUNS=1 NSTEPS=$STEPS bench/liggghts/run_bench.sh $BED   (LIGGGHTS 3.8, $THREADS MPI ranks)"
  echo "#   build/scoopsim bench settle --particles $PARTICLES --steps $STEPS --threads $THREADS"
  printf '%s\n' "${lines[@]}"
  printf '%s\n' "${lines[@]}" | /usr/bin/python3 -c '
import statistics, sys
rows = [l.split() for l in sys.stdin if l.strip()]
med = lambda k: statistics.median(float(r[k]) for r in rows)
print("# medians: liggghts %.2f M, scoopsim %.2f M, ratio %.2f" % (med(1), med(4), med(7)))'
} >"$OUT"
tail -n 1 "$OUT"
echo "compare_liggghts: wrote $OUT"

#!/usr/bin/env bash
# The full-scale dig's step in mid-pass, without running the pass up to there: the tiled
# 300,000-sphere bed of scenes/paper/snow_b15_pass1_tiled.yaml in its state AT seconds into the
# dig (positions, velocities, spins, sleep flags), stepped by `scoopsim bench step` without the
# scoop. Prepared once under bench/cache/ (git-ignored): the settle benchmark's bed (about 9 min
# the first time), its 3 x 2 tiling, a dig run stopped at AT with a snapshot there, the state.
#
#   bench/run_dig_step.sh                       # AT=0.7 s, 5 runs of 1500 steps, 2 threads
#   BINS="build/scoopsim /tmp/old/scoopsim" NRUNS=8 bench/run_dig_step.sh   # interleaved A/B
#   ARM=1 bench/run_dig_step.sh                 # each run also with the lander's arm stepped
#                                               # beside the bed (bench step --arm), interleaved
#
# Output: one JSON line per run, then the median ms_per_step of each binary.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
AT=${AT:-0.7}
NRUNS=${NRUNS:-5}
STEPS=${STEPS:-1500}
WARM=${WARM:-400}
THREADS=${THREADS:-2}
BINS=${BINS:-"$ROOT/build/scoopsim"}
BIN=${BINS%% *}
CACHE="$ROOT/bench/cache"
SCENE="$ROOT/scenes/paper/snow_b15_pass1_tiled.yaml"
mkdir -p "$CACHE"

"$BIN" bench settle --particles 50000 --steps 1 --threads "$THREADS" >/dev/null  # makes the bed once
TILED="$CACHE/bed_snow_tiled.h5"
[ -s "$TILED" ] || /usr/bin/python3 "$ROOT/tools/tile_bed.py" "$CACHE/settle_50000.h5" \
  --box 0 0 0.2 0.1 --tiles 3 2 -o "$TILED"
STATE="$CACHE/dig_state_$AT.h5"
if [ ! -s "$STATE" ]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  # The scene with absolute paths, the cached bed and a snapshot at AT (the step is 0.3 t_R of
  # 3.5 mm snow: 9.66 us).
  at_steps=$(awk "BEGIN{print int($AT / 9.66e-6)}")
  sed -e "s|^materials: .*|materials: $ROOT/scenes/materials.yaml|" \
      -e "s|file: .*|file: $TILED|" -e "s|mesh: \.\./\.\./assets|mesh: $ROOT/assets|" \
      -e "s|^output: .*|output: {flush_seconds: 10, snapshot_every: $at_steps}|" \
      "$SCENE" > "$work/dig.yaml"
  "$BIN" run "$work/dig.yaml" -o "$work/dig.h5" --threads "$THREADS" \
    --stop-after "$(awk "BEGIN{print $AT + 0.01}")"
  /usr/bin/python3 "$ROOT/bench/dig_state.py" "$work/dig.h5" "$TILED" -o "$STATE"
fi
# A plain scene on the state: the dig scene's keys without the dig.
sed -e "s|^materials: .*|materials: $ROOT/scenes/materials.yaml|" -e "s|file: .*|file: $STATE|" \
    -e "/^dig:/,/^[a-z]/{/^dig:/d;/^  /d}" -e "/^output:/d" "$SCENE" > "$CACHE/dig_state.yaml"

ARM=${ARM:-0}
for r in $(seq "$NRUNS"); do
  for b in $BINS; do
    echo "$b $("$b" bench step "$CACHE/dig_state.yaml" --steps "$STEPS" --warm "$WARM" --threads "$THREADS")"
    if [ "$ARM" = 1 ]; then
      echo "$b+arm $("$b" bench step "$CACHE/dig_state.yaml" --steps "$STEPS" --warm "$WARM" \
        --threads "$THREADS" --arm "$ROOT/assets/lander_arm.urdf")"
    fi
  done
done | tee "$CACHE/dig_step_last.txt"
for b in $BINS; do
  for v in "$b" "$b+arm"; do
    grep -q "^$v " "$CACHE/dig_step_last.txt" || continue
    grep "^$v " "$CACHE/dig_step_last.txt" | sed 's/.*"ms_per_step":\([0-9.]*\).*/\1/' | sort -n |
      awk -v b="$v" '{a[NR]=$1} END{printf "%s: median %.4f ms a step (%d runs, min %.4f, max %.4f)\n", b, a[int((NR+1)/2)], NR, a[1], a[NR]}'
  done
  grep "^$b+arm " "$CACHE/dig_step_last.txt" | sed 's/.*"arm_ms_per_step":\([0-9.]*\).*/\1/' |
    sort -n | awk -v b="$b" 'NF{a[NR]=$1} END{if (NR) printf "%s: the arm alone, median %.5f ms a step (min %.5f, max %.5f)\n", b, a[int((NR+1)/2)], a[1], a[NR]}'
done

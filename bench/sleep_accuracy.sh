#!/usr/bin/env bash
# What sleeping costs in accuracy and buys in speed (the dig issue's 2% criterion): runs a dig
# scene with sleeping on and off and compares peak and mean |F| on the scoop and the wall time.
#   bench/sleep_accuracy.sh [SCENE] [THREADS]      (default scenes/quick_dig.yaml, 2)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/quick_dig.yaml}
threads=${2:-2}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The bed once, so both runs start from the same state.
build/scoopsim bed "$scene" -o "$work/bed.h5" --threads "$threads" -q
for mode in true false; do
  sed -e "s|^sleep:.*|sleep: {enabled: $mode}|" \
      -e "s|^\(  *\)count: \(.*\)|&\n\1file: $work/bed.h5|" "$scene" > "$work/scene_$mode.yaml"
  sed -i "s|mesh: \.\./assets|mesh: $PWD/assets|; s|^materials: materials.yaml|materials: $PWD/scenes/materials.yaml|" \
      "$work/scene_$mode.yaml"
  start=$(date +%s.%N)
  build/scoopsim run "$work/scene_$mode.yaml" -o "$work/run_$mode.h5" --threads "$threads" -q \
      2> "$work/log_$mode.txt"
  end=$(date +%s.%N)
  line=$(grep "scoopsim: dig:" "$work/log_$mode.txt")
  echo "sleep=$mode wall_s=$(awk "BEGIN{printf \"%.1f\", $end - $start}") $line"
done

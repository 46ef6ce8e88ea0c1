#!/usr/bin/env bash
# A dig scene under each contact law (issue 18): peak and mean |F| and peak |T| on the scoop.
#   bench/contact_law_digs.sh [SCENE] [THREADS]     (default scenes/quick_dig.yaml, 2)
# Laws (the materials file with a contact_law line in front):
#   edem/standard (the default), cdt/standard, legacy/standard, legacy/exact_restitution (the law
#   before issue 18, bit for bit).
# Beds: BED=own (default) pours each law's own bed, as a user's run would; BED=shared pours one
# bed under the default law (`scoopsim bed`) and digs it under each law, so that only the dig's
# contacts differ.
# LAWS (default all four, as above) picks some: LAWS=edem/standard.
# Appends a row per run to bench/results/$MACHINE/contact_law_digs.csv; prints the dig lines.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
scene=$(cd "$(dirname "${1:-$ROOT/scenes/quick_dig.yaml}")" && pwd)/$(basename "${1:-quick_dig.yaml}")
threads=${2:-2}
BED=${BED:-own}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
CSV="$ROOT/bench/results/$MACHINE/contact_law_digs.csv"
mkdir -p "$(dirname "$CSV")"
[ -s "$CSV" ] || echo "date,commit,scene,rolling_model,damping,bed,threads,peak_abs_f_n,mean_abs_f_n,peak_abs_t_nm,wall_s" >"$CSV"
commit=$(git -C "$ROOT" rev-parse --short HEAD)
work=$(mktemp -d)
dir=$(dirname "$scene")
# The variant scenes sit beside the scene (its relative paths stay valid), under hidden names.
tag=".law_$$_"
trap 'rm -rf "$work" "$dir/$tag"*' EXIT
materials=$(sed -n 's|^materials: *||p' "$scene")
case "$materials" in /*) ;; *) materials="$dir/$materials" ;; esac

if [ "$BED" = shared ]; then
  "$ROOT/build/scoopsim" bed "$scene" -o "$work/bed.h5" --threads "$threads" -q
fi
for law in ${LAWS:-edem/standard cdt/standard legacy/standard legacy/exact_restitution}; do
  model=${law%/*}
  damping=${law#*/}
  { echo "contact_law: {rolling_model: $model, damping: $damping}"; cat "$materials"; } \
    >"$work/materials_${model}_${damping}.yaml"
  variant="$dir/$tag${model}_$damping.yaml"
  sed "s|^materials: .*|materials: $work/materials_${model}_${damping}.yaml|" "$scene" >"$variant"
  if [ "$BED" = shared ]; then
    sed -i "s|^\(  *\)count: \(.*\)|&\n\1file: $work/bed.h5|" "$variant"
  fi
  start=$(date +%s.%N)
  "$ROOT/build/scoopsim" run "$variant" -o "$work/run.h5" --threads "$threads" -q 2>"$work/log"
  end=$(date +%s.%N)
  line=$(grep "scoopsim: dig: .*peak |F|" "$work/log")
  echo "$model/$damping bed=$BED: $line"
  /usr/bin/python3 - "$line" "$CSV" "$commit" "${scene#"$ROOT"/}" "$model" "$damping" "$BED" \
    "$threads" "$(awk "BEGIN{printf \"%.1f\", $end - $start}")" <<'PY'
import datetime, re, sys
line, csv, commit, scene, model, damping, bed, threads, wall = sys.argv[1:]
f = re.search(r"peak \|F\| ([0-9.e+-]+) N, mean \|F\| ([0-9.e+-]+) N", line)
t = re.search(r"peak \|T\| ([0-9.e+-]+) N m", line)
with open(csv, "a") as out:
    out.write(",".join([datetime.date.today().isoformat(), commit, scene, model, damping, bed,
                        threads, f.group(1), f.group(2), t.group(1), wall]) + "\n")
PY
done

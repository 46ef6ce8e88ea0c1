#!/usr/bin/env bash
# The render benchmark of scoopsim: `scoopsim bench render` NRUNS times per rasteriser thread
# count (LP_NUM_THREADS), then the medians. Frames are 1280x720 PNGs of a bed the project made:
# $BED, else out/bench/render_bed.h5, made once by `scoopsim bed scenes/settle_small.yaml` (2000
# settled snow spheres, r 1.75 mm; about a minute) and laid side by side up to $PARTICLES. Frames
# go to a temporary folder (removed) and are timed including the PNG writing.
#
#   bench/run_render.sh                          # 200,000 particles, 20 frames, threads 1 and 2
#   BED=out/bed.h5 bench/run_render.sh           # another bed (or a run's output: its last snapshot)
#   PARTICLES=100000 THREADS="2" bench/run_render.sh
#   EXTRA="--no-cull" bench/run_render.sh        # without occlusion culling
#
# Output: one JSON line per run on stdout, then one summary line per thread count (medians);
# rows appended to bench/results/$MACHINE/scoopsim_render.csv with the CPU model in a comment.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PARTICLES=${PARTICLES:-200000}
FRAMES=${FRAMES:-20}
NRUNS=${NRUNS:-5}
THREADS=${THREADS:-"1 2"}
EXTRA=${EXTRA:-}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
BIN="$ROOT/build/scoopsim"
BED=${BED:-$ROOT/out/bench/render_bed.h5}
if [ ! -s "$BED" ]; then
  "$BIN" bed "$ROOT/scenes/settle_small.yaml" -o "$BED" --quiet
fi
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/scoopsim_render.csv"
mkdir -p "$RESDIR"

if [ ! -s "$CSV" ]; then
  {
    echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores"
    echo "date,particles,frames,width,height,threads,png_level,cull,fps,draw_ms,png_ms,png_kb,drawn"
  } >"$CSV"
fi

for t in $THREADS; do
  runs=()
  for r in $(seq "$NRUNS"); do
    # shellcheck disable=SC2086  # EXTRA holds separate options
    line=$("$BIN" bench render --bed "$BED" --particles "$PARTICLES" --frames "$FRAMES" --threads "$t" $EXTRA)
    echo "$line"
    /usr/bin/python3 - "$line" "$CSV" <<'PY'
import json, sys, datetime
d = json.loads(sys.argv[1])
with open(sys.argv[2], "a") as f:
    f.write(",".join(str(x) for x in [datetime.datetime.utcnow().isoformat(timespec="seconds"),
        d["particles"], d["frames"], d["width"], d["height"], d["threads"], d["png_level"],
        str(d["cull"]).lower(), d["fps"], d["draw_ms"], d["png_ms"], d["png_kb"], d["drawn"]]) + "\n")
PY
    runs+=("$line")
  done
  printf '%s\n' "${runs[@]}" | /usr/bin/python3 -c '
import json, statistics, sys
runs = [json.loads(l) for l in sys.stdin if l.strip()]
med = lambda k: statistics.median(r[k] for r in runs)
print(json.dumps({"summary": "median", "runs": len(runs), "particles": runs[0]["particles"],
                  "frames": runs[0]["frames"], "width": runs[0]["width"],
                  "height": runs[0]["height"], "threads": runs[0]["threads"],
                  "cull": runs[0]["cull"], "fps": med("fps"), "draw_ms": med("draw_ms"),
                  "png_ms": med("png_ms"), "drawn": med("drawn")}))'
done

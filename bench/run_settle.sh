#!/usr/bin/env bash
# The settle benchmark of scoopsim: `scoopsim bench settle` NRUNS times per thread count, then the
# medians. The settled bed is prepared once and cached under bench/cache/ (git-ignored).
#
#   bench/run_settle.sh                      # 50,000 particles, 2000 steps, threads 1 and 2
#   PARTICLES=25000 THREADS="2" bench/run_settle.sh
#
# Output: one JSON line per run on stdout, then one summary line per thread count (medians);
# rows appended to bench/results/$MACHINE/scoopsim_settle.csv with the CPU model in a comment.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PARTICLES=${PARTICLES:-50000}
STEPS=${STEPS:-2000}
NRUNS=${NRUNS:-5}
THREADS=${THREADS:-"1 2"}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
BIN="$ROOT/build/scoopsim"
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/scoopsim_settle.csv"
mkdir -p "$RESDIR"

# Prepare (or load) the cached bed once, outside the timed runs.
"$BIN" bench settle --particles "$PARTICLES" --steps 1 --threads 2 >/dev/null

if [ ! -s "$CSV" ]; then
  {
    echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores"
    echo "date,particles,steps,threads,wall_s,particle_steps_per_s,contacts_per_particle,peak_rss_mb,state_hash"
  } >"$CSV"
fi

for t in $THREADS; do
  rates=()
  for r in $(seq "$NRUNS"); do
    line=$("$BIN" bench settle --particles "$PARTICLES" --steps "$STEPS" --threads "$t")
    echo "$line"
    /usr/bin/python3 - "$line" "$CSV" <<'PY'
import json, sys, datetime
d = json.loads(sys.argv[1])
with open(sys.argv[2], "a") as f:
    f.write(",".join(str(x) for x in [datetime.datetime.utcnow().isoformat(timespec="seconds"),
        d["particles"], d["steps"], d["threads"], d["wall_s"], d["particle_steps_per_s"],
        d["contacts_per_particle"], d["peak_rss_mb"], d["state_hash"]]) + "\n")
PY
    rates+=("$line")
  done
  printf '%s\n' "${rates[@]}" | /usr/bin/python3 -c '
import json, statistics, sys
runs = [json.loads(l) for l in sys.stdin if l.strip()]
med = lambda k: statistics.median(r[k] for r in runs)
print(json.dumps({"summary": "median", "runs": len(runs), "particles": runs[0]["particles"],
                  "steps": runs[0]["steps"], "threads": runs[0]["threads"],
                  "wall_s": med("wall_s"), "particle_steps_per_s": med("particle_steps_per_s"),
                  "peak_rss_mb": med("peak_rss_mb"),
                  "state_hashes": sorted({r["state_hash"] for r in runs})}))'
done

#!/usr/bin/env bash
# A/B speed of two (or more) scoopsim binaries on one benchmark command, as interleaved runs
# (A, B, A, B, ...) so that a shared host's slow spells hit both alike. Prints each run's JSON
# line, then per binary the median and the range of the chosen figure and the ratio of medians
# against the first binary; appends one CSV row per run to bench/results/$MACHINE/$CSV.
#
#   BINS="/tmp/base/scoopsim build/scoopsim" bench/interleave.sh bench settle --threads 2
#   BINS="/tmp/base/scoopsim build/scoopsim" KEY=ms_per_step \
#     bench/interleave.sh bench step bench/cache/dig_state.yaml --threads 2
#
# Environment: BINS (required), NRUNS (5), KEY (the JSON figure: particle_steps_per_s for
# settle, ms_per_step for step), LABEL (a word for the CSV rows), CSV (interleaved_pairs.csv),
# MACHINE (hostname), QUIET_WAIT (seconds, default 0: before each run, wait up to this long until
# no compiler, test binary or other scoopsim runs on the host, as a shared host needs), PHASES
# (1: also a row per run for each of the JSON's other ms_* figures, the phases of `bench step`,
# and their medians at the end).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
: "${BINS:?set BINS to the binaries to compare, first = baseline}"
NRUNS=${NRUNS:-5}
KEY=${KEY:-particle_steps_per_s}
LABEL=${LABEL:-$1-$2}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/${CSV:-interleaved_pairs.csv}"
mkdir -p "$RESDIR"
[ -s "$CSV" ] || echo "date,label,binary,run,key,value,state_hash" >"$CSV"

. "$ROOT/bench/wait_quiet.sh"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
for r in $(seq "$NRUNS"); do
  for b in $BINS; do
    wait_quiet
    line=$("$b" "$@")
    echo "$b $line" | tee -a "$log"
    /usr/bin/python3 - "$line" "$CSV" "$LABEL" "$b" "$r" "$KEY" "${PHASES:-0}" <<'PY'
import datetime, json, sys
d = json.loads(sys.argv[1])
_, csv, label, binary, run, key, phases = sys.argv[1:]
keys = [key] + ([k for k in d if k.startswith("ms_") and k != key] if phases == "1" else [])
now = datetime.datetime.utcnow().isoformat(timespec="seconds")
with open(csv, "a") as f:
    for k in keys:
        f.write(",".join([now, label, binary, run, k, str(d[k]), d.get("state_hash", "")]) + "\n")
PY
  done
done
/usr/bin/python3 - "$log" "$KEY" "${PHASES:-0}" $BINS <<'PY'
import json, statistics, sys
log, key, phases, bins = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
runs_of = [(b, json.loads(j)) for b, j in (l.split(" ", 1) for l in open(log))]
# (the phases every binary's JSON has: an older binary may lack a newer one's)
common = set.intersection(*(set(d) for _, d in runs_of))
keys = [key] + ([k for k in runs_of[0][1] if k.startswith("ms_") and k != key and k in common]
                if phases == "1" else [])
for k in keys:
    runs = {b: [d[k] for bb, d in runs_of if bb == b] for b in bins}
    base = statistics.median(runs[bins[0]])
    for b in bins:
        v = runs[b]
        m = statistics.median(v)
        print(f"{b}: {k} median {m:.6g} (min {min(v):.6g}, max {max(v):.6g}, {len(v)} runs); "
              f"ratio to {bins[0]}: {m / base if base else float('nan'):.4f}")
PY

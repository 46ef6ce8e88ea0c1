#!/usr/bin/env bash
# A busy core (issue 22): a dig on 1 and 2 threads, with the machine as it is ("quiet") and with
# one core held by a fixed busy loop (a shell spinning `while :; do :; done`, not pinned: the
# scheduler places it, as another user's job; started 0.5 s before the run), interleaved: each round runs every binary in every
# configuration (1 thread quiet, 2 quiet, 1 busy, 2 busy). Prints each run's wall time and
# phases (the wall time as simulated / the printed real-time factor: 3 digits), then per binary
# the medians, ranges and the ratios 2-busy / 1-quiet, 2-busy / 1-busy
# and 1-quiet / 2-quiet (the 2-thread speedup); appends one CSV row per run.
#
#   BINS="/tmp/scoopsim_busy_base build/scoopsim" bench/busy_core.sh
#
# Environment: BINS (default build/scoopsim; the first is the baseline), ROUNDS (5), SCENE
# (scenes/bench/dig_7mm.yaml; its bed is made once into bench/cache/dig_7mm_bed.h5), STOP
# (simulated seconds of the dig, 0.1: 6211 steps; the journal's rows used 0.05), OMP_WAIT_POLICY
# (as given; unset: scoopsim's own default since 37ccb71, sleeping threads, and the runtime's,
# spinning, for older binaries), EXTRA (more options for `scoopsim run`), CSV (busy_core.csv), MACHINE
# (hostname), LOCK (a file taken with flock around each timed run: /tmp/scoopsim_bench.lock, so
# that timed runs of several users never overlap), QUIET_WAIT (bench/wait_quiet.sh).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
BINS=${BINS:-build/scoopsim}
ROUNDS=${ROUNDS:-5}
SCENE=${SCENE:-scenes/bench/dig_7mm.yaml}
STOP=${STOP:-0.1}
EXTRA=${EXTRA:-}
LOCK=${LOCK:-/tmp/scoopsim_bench.lock}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="$ROOT/bench/results/$MACHINE"
CSV="$RESDIR/${CSV:-busy_core.csv}"
mkdir -p "$RESDIR"
[ -s "$CSV" ] || echo "date,binary,wait_policy,stop_s,round,threads,core,wall_s,pairs_s,integrate_s,mesh_s,near_s,rebuild_s,fewer_pct,state_hash" >"$CSV"
policy=${OMP_WAIT_POLICY:-default}

# The bed, once (the scene's own pour: scenes/sleep_check.yaml's).
if [ ! -s bench/cache/dig_7mm_bed.h5 ]; then
  mkdir -p bench/cache
  first=${BINS%% *}
  "$first" bed scenes/sleep_check.yaml -o bench/cache/dig_7mm_bed.h5 -q
fi

. "$ROOT/bench/wait_quiet.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# One timed run, under the lock (with `busy`, the busy loop runs only while the lock is held, so
# it never slows another user's timed run): prints "wall pairs integrate mesh near rebuild
# fewer% hash".
run_one() {
  local bin=$1 threads=$2 core=$3 out=$work/run.h5 log=$work/log.txt
  wait_quiet
  flock "$LOCK" bash -c '
    if [ "$1" = busy ]; then bash -c "while :; do :; done" & spin=$!; sleep 0.5; fi
    "${@:2}"; rc=$?
    if [ -n "${spin:-}" ]; then kill "$spin"; wait "$spin" 2>/dev/null; fi
    exit $rc' _ "$core" "$bin" run "$SCENE" -o "$out" --threads "$threads" --stop-after "$STOP" \
    -q $EXTRA 2>"$log" || { cat "$log" >&2; return 1; }
  local hash
  hash=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1],'r').attrs['state_hash'])" "$out" 2>/dev/null || echo -)
  awk -v hash="$hash" '
    # The dig wall time to 3 digits: simulated time / the printed real-time factor (the
    # printed wall time has one decimal: 2-4% steps on these runs).
    /scoopsim: dig: .* s simulated/ {
      for (i = 1; i <= NF; ++i) if ($(i+1) == "s" && $(i+2) ~ /^simulated/) sim = $i
    }
    /scoopsim: dig: .* s wall/ {
      for (i = 1; i <= NF; ++i) {
        if ($(i+1) == "s" && $(i+2) == "wall") wall = $i
        if ($(i+1) == "x" && $(i+2) == "real") { rtf = $i; sub("[(]", "", rtf) }
        if ($i == "pairs" || $i == "integrate" || $i == "mesh" || $i == "near" || $i == "rebuild") t[$i] = $(i+1)
      }
      if (sim != "" && rtf + 0 > 0) wall = sprintf("%.4g", sim / rtf)
    }
    /scoopsim: threads:/ { for (i = 1; i <= NF; ++i) if ($i == "on") { f = $(i+1); sub("%", "", f) } }
    END { printf "%s %s %s %s %s %s %s %s\n", wall, t["pairs"], t["integrate"], t["mesh"], t["near"], t["rebuild"], (f == "" ? "-" : f), hash }' "$log"
}

for r in $(seq "$ROUNDS"); do
  for core in quiet busy; do
    for b in $BINS; do
      for threads in 1 2; do
        read -r wall pairs integ mesh near rebuild fewer hash < <(run_one "$b" "$threads" "$core")
        echo "round $r $core $b threads $threads: wall $wall s (pairs $pairs, integrate $integ, mesh $mesh, near $near, rebuild $rebuild; fewer threads on $fewer% of steps) $hash"
        echo "$(date -u +%Y-%m-%dT%H:%M:%S),$b,$policy,$STOP,$r,$threads,$core,$wall,$pairs,$integ,$mesh,$near,$rebuild,$fewer,$hash" >>"$CSV"
      done
    done
  done
done

# Medians, ranges and ratios of this invocation's rows.
tail -n $((ROUNDS * 4 * $(echo "$BINS" | wc -w))) "$CSV" | /usr/bin/python3 -c '
import collections, statistics, sys
rows = [l.strip().split(",") for l in sys.stdin if l.strip()]
wall = collections.defaultdict(list)
for r in rows:
    wall[(r[1], r[5], r[6])].append(float(r[7]))
for b in dict.fromkeys(r[1] for r in rows):
    m = {k[1:]: statistics.median(v) for k, v in wall.items() if k[0] == b}
    for k in sorted(m):
        v = wall[(b,) + k]
        print(f"{b}: {k[0]} thread(s) {k[1]}: median {m[k]:.2f} s, range {min(v):.2f}-{max(v):.2f}")
    q1, q2, b1, b2 = m[("1", "quiet")], m[("2", "quiet")], m[("1", "busy")], m[("2", "busy")]
    print(f"{b}: 2-busy / 1-quiet {b2 / q1:.2f}, 2-busy / 1-busy {b2 / b1:.2f}, "
          f"speedup 1-quiet / 2-quiet {q1 / q2:.2f}")
'

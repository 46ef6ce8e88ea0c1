#!/bin/bash
# ---------------------------------------------------------------------------
# run_bench.sh [BED.h5] -- LIGGGHTS particle-steps/s on the settled bed.
#
#   bench/liggghts/run_bench.sh                # LIGGGHTS-made bed (cached)
#   bench/liggghts/run_bench.sh bed.h5         # scoopsim bed, converted
#
# Environment knobs (defaults in brackets):
#   NRUNS [5]        timed runs per rank count
#   NSTEPS [2000]    steps per timed run
#   RANKS ["1 2"]    MPI rank counts to run
#   MAKE_RANKS [2]   ranks used by in.make_bed
#   REMAKE_BED [0]   1: rebuild the cached LIGGGHTS bed
#   MAKE_VARS [""]   extra liggghts arguments for in.make_bed, e.g.
#                    "-var vfinal 0.00055" (scoopsim's settle criterion)
#   MACHINE [hostname]  results go to bench/results/$MACHINE/liggghts_settle.csv
#   RESULTS_DIR, CACHE_DIR  override bench/results/$MACHINE, bench/cache/liggghts
#   KEEP_LOGS        directory to keep the LIGGGHTS logs and time -v output in
#   QUIET_BUSY [0.15]   before each timed run wait until the machine is idle:
#                       fraction of all CPUs busy (sampled over 2 s) below this
#   QUIET_WAIT [300]    ...but wait at most this many seconds per run (then run
#                       anyway; the row is marked "contended")
#
# Each row records cpu_busy_before (load just before the run),
# others_busy_during (CPU time used by other processes during the run, as a
# fraction of all CPUs: /proc/stat busy time minus the ranks' user+sys time)
# and cpu_pct_min (lowest "Percent of CPU this job got" over the ranks, from
# /usr/bin/time -v).  A run is marked contended when cpu_busy_before or
# others_busy_during > QUIET_BUSY, or cpu_pct_min < 90: on a shared 2-core
# machine such runs are not representative; the summary medians use only
# uncontended runs when there are any.
#
# Output: one JSON line per run and one summary JSON line (medians) per rank
# count on stdout; CSV in bench/results/$MACHINE/liggghts_settle.csv.
# Needs: liggghts, mpirun (openmpi-bin), /usr/bin/time (package "time"),
#        /usr/bin/python3 with h5py + numpy (only to convert an .h5 bed).
# ---------------------------------------------------------------------------
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CACHE="${CACHE_DIR:-$ROOT/bench/cache/liggghts}"
NRUNS=${NRUNS:-5}
NSTEPS=${NSTEPS:-2000}
RANKS=${RANKS:-"1 2"}
MAKE_RANKS=${MAKE_RANKS:-2}
REMAKE_BED=${REMAKE_BED:-0}
QUIET_BUSY=${QUIET_BUSY:-0.15}
QUIET_WAIT=${QUIET_WAIT:-300}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
RESDIR="${RESULTS_DIR:-$ROOT/bench/results/$MACHINE}"
CSV="$RESDIR/liggghts_settle.csv"
PY=/usr/bin/python3

log() { echo "[run_bench] $*" >&2; }

# fraction of all CPUs busy over a 2 s window (from /proc/stat)
cpu_busy() {
    local a b
    a=($(head -1 /proc/stat)); sleep 2; b=($(head -1 /proc/stat))
    awk -v u1="${a[1]}" -v n1="${a[2]}" -v s1="${a[3]}" -v i1="${a[4]}" -v w1="${a[5]}" \
        -v q1="${a[6]}" -v sq1="${a[7]}" -v st1="${a[8]}" \
        -v u2="${b[1]}" -v n2="${b[2]}" -v s2="${b[3]}" -v i2="${b[4]}" -v w2="${b[5]}" \
        -v q2="${b[6]}" -v sq2="${b[7]}" -v st2="${b[8]}" 'BEGIN{
        busy=(u2+n2+s2+q2+sq2+st2)-(u1+n1+s1+q1+sq1+st1); idle=(i2+w2)-(i1+w1);
        tot=busy+idle; printf "%.3f", (tot>0 ? busy/tot : 0) }'
}

# total busy CPU time of the machine so far, in clock ticks (all CPUs)
busy_ticks() {
    awk '/^cpu /{print $2+$3+$4+$7+$8+$9; exit}' /proc/stat
}
CLK_TCK=$(getconf CLK_TCK 2>/dev/null || echo 100)

# wait (at most QUIET_WAIT s) until cpu_busy < QUIET_BUSY; prints the last value
wait_quiet() {
    local t0 b
    t0=$(date +%s)
    while :; do
        b=$(cpu_busy)
        if awk -v b="$b" -v q="$QUIET_BUSY" 'BEGIN{exit !(b < q)}'; then break; fi
        if [ $(( $(date +%s) - t0 )) -ge "$QUIET_WAIT" ]; then
            log "machine still busy ($b of all CPUs) after ${QUIET_WAIT}s, running anyway"
            break
        fi
        log "machine busy ($b of all CPUs used by other processes), waiting"
        sleep 8
    done
    echo "$b"
}

command -v liggghts >/dev/null || { log "liggghts not found (apt-get install liggghts)"; exit 1; }
command -v mpirun   >/dev/null || { log "mpirun not found (apt-get install openmpi-bin)"; exit 1; }
if [ ! -x /usr/bin/time ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        log "/usr/bin/time missing, installing package 'time'"
        apt-get install -y time >&2
    else
        log "/usr/bin/time missing (apt-get install time)"; exit 1
    fi
fi
MPIRUN=(mpirun)
[ "$(id -u)" = 0 ] && MPIRUN+=(--allow-run-as-root)

mkdir -p "$CACHE" "$RESDIR"
# Resolve the bed's path before leaving the caller's folder.
if [ $# -ge 1 ]; then BED_ARG=$(cd "$(dirname "$1")" && pwd)/$(basename "$1"); fi
# LIGGGHTS runs in scratch folders (it may drop restart_forced_*.data files
# into its working folder when it is killed); -var dir tells the inputs where
# in.material and in.walls are.

# ---------------------------------------------------------------- the bed --
if [ $# -ge 1 ]; then
    BED_SRC=$BED_ARG
    DATA="$CACHE/$(basename "${1%.h5}").data"
    log "converting $BED_SRC -> $DATA"
    "$PY" "$HERE/h5_to_liggghts.py" "$BED_SRC" "$DATA" >&2
    BED_NAME=$(basename "$1")
else
    DATA="$CACHE/bed_make_bed.data"
    BED_NAME="liggghts_make_bed"
    if [ "$REMAKE_BED" = 1 ] || [ ! -s "$DATA" ]; then
        log "making the bed with in.make_bed on $MAKE_RANKS ranks (takes minutes)"
        MAKEDIR=$(mktemp -d "${TMPDIR:-/tmp}/liggghts_make_bed.XXXXXX")
        t0=$(date +%s.%N)
        if ! ( cd "$MAKEDIR" && "${MPIRUN[@]}" -np "$MAKE_RANKS" liggghts -nocite \
                 -in "$HERE/in.make_bed" -var dir "$HERE" -var out "$MAKEDIR/bed.data" ${MAKE_VARS:-} \
                 -log "$MAKEDIR/make_bed.log" -screen none ); then
            mkdir -p "$CACHE"; cp "$MAKEDIR/make_bed.log" "$CACHE/make_bed.failed.log" 2>/dev/null || true
            rm -rf "$MAKEDIR"
            log "in.make_bed failed, see $CACHE/make_bed.failed.log"; exit 1
        fi
        t1=$(date +%s.%N)
        mkdir -p "$CACHE"
        cp "$MAKEDIR/make_bed.log" "$CACHE/make_bed.log"
        mv "$MAKEDIR/bed.data" "$DATA"
        rm -rf "$MAKEDIR"
        MAKE_S=$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')
        echo "$MAKE_S" > "$CACHE/make_bed.wall_s"
        log "bed made in $MAKE_S s wall: $(grep 'make_bed: done' "$CACHE/make_bed.log" | tail -1)"
    else
        log "using cached bed $DATA (made in $(cat "$CACHE/make_bed.wall_s" 2>/dev/null || echo '?') s)"
    fi
fi

# ---------------------------------------------------------------- the runs --
RUNDIR=$(mktemp -d "${TMPDIR:-/tmp}/liggghts_bench.XXXXXX")
if [ -n "${KEEP_LOGS:-}" ]; then
    trap 'mkdir -p "$KEEP_LOGS" && cp -r "$RUNDIR"/. "$KEEP_LOGS"/ && rm -rf "$RUNDIR"' EXIT
else
    trap 'rm -rf "$RUNDIR"' EXIT
fi
RAW="$RUNDIR/raw.tsv"
: > "$RAW"

for R in $RANKS; do
    for i in $(seq 1 "$NRUNS"); do
        d="$RUNDIR/r${R}_$i"; mkdir -p "$d"
        busy=$(wait_quiet)
        b0=$(busy_ticks); t0=$(date +%s.%N)
        # one /usr/bin/time per rank -> peak RSS of every rank
        ( cd "$d" && "${MPIRUN[@]}" -np "$R" sh -c \
            'exec /usr/bin/time -v -o "$0/time.${OMPI_COMM_WORLD_RANK:-0}" liggghts -nocite "$@"' "$d" \
            -in "$HERE/in.bench" -var dir "$HERE" -var data "$DATA" -var nsteps "$NSTEPS" \
            -log "$d/log.liggghts" -screen none )
        b1=$(busy_ticks); t1=$(date +%s.%N)
        # CPU used by other processes during the run: machine busy time minus
        # this run's own user+sys time (all ranks), as a fraction of all CPUs
        ours=$(grep -hE '(User|System) time \(seconds\)' "$d"/time.* | awk '{s+=$NF} END{print s+0}')
        others=$(awk -v b0="$b0" -v b1="$b1" -v t0="$t0" -v t1="$t1" -v hz="$CLK_TCK" \
                     -v ours="$ours" -v nc="$(nproc)" 'BEGIN{
                 o=(b1-b0)/hz-ours; if (o<0) o=0; printf "%.3f", o/(nc*(t1-t0)) }')
        line=$(grep -E '^Loop time of .* steps with .* atoms' "$d/log.liggghts" | head -1)
        [ -n "$line" ] || { log "no 'Loop time' line in $d/log.liggghts"; exit 1; }
        rss=$(grep -h 'Maximum resident set size' "$d"/time.* | awk '{print $NF}' | tr '\n' ' ')
        cpp=$(sed -n 's/^in.bench: contacts\/particle \([^,]*\),.*/\1/p' "$d/log.liggghts" | tail -1)
        pct=$(grep -h 'Percent of CPU this job got' "$d"/time.* | awk '{gsub("%","",$NF); print $NF}' | sort -n | head -1)
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$R" "$i" "$line" "$rss" "${cpp:-nan}" "$busy" "${pct:-0}" "$others" >> "$RAW"
        log "ranks=$R run=$i: $line (busy before $busy, others during $others, min cpu% $pct)"
    done
done

CPU_MODEL=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: *//')
CPU_MODEL="$CPU_MODEL (family $(grep -m1 'cpu family' /proc/cpuinfo | sed 's/.*: *//') model $(grep -m1 '^model[[:space:]]*:' /proc/cpuinfo | sed 's/.*: *//'))"
NCORES=$(nproc)
"$PY" - "$RAW" "$CSV" "$CPU_MODEL" "$NCORES" "$BED_NAME" "$MACHINE" "$QUIET_BUSY" <<'PYEOF'
import json, re, statistics, sys, datetime
raw, csv, cpu, ncores, bed, machine, quiet = sys.argv[1:8]
quiet = float(quiet)
pat = re.compile(r"Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms")
rows = []
for ln in open(raw):
    r, i, line, rss, cpp, busy, pct, others = ln.rstrip("\n").split("\t")
    m = pat.search(line)
    x, p, n, mm = float(m.group(1)), int(m.group(2)), int(m.group(3)), int(m.group(4))
    rss_kb = [int(v) for v in rss.split()]
    row = {"code": "liggghts", "ranks": p, "run": int(i), "particles": mm,
           "steps": n, "wall_s": round(x, 4),
           "particle_steps_per_s": round(mm * n / x),
           "peak_rss_mb": round(max(rss_kb) / 1024.0, 1),          # per rank (max)
           "peak_rss_total_mb": round(sum(rss_kb) / 1024.0, 1),    # all ranks
           "contacts_per_particle": float(cpp),
           "cpu_busy_before": float(busy), "others_busy_during": float(others),
           "cpu_pct_min": int(float(pct)),
           "contended": bool(float(busy) > quiet or float(others) > quiet
                             or float(pct) < 90),
           "bed": bed}
    rows.append(row)
    print(json.dumps(row))
with open(csv, "w") as f:
    f.write("# LIGGGHTS-PUBLIC 3.8 settled-bed benchmark, bench/liggghts/run_bench.sh\n")
    f.write("# machine: %s; cpu: %s; cores: %s; date: %s\n"
            % (machine, cpu, ncores, datetime.datetime.now().isoformat(timespec="seconds")))
    keys = ["code", "ranks", "run", "particles", "steps", "wall_s",
            "particle_steps_per_s", "peak_rss_mb", "peak_rss_total_mb",
            "contacts_per_particle", "cpu_busy_before", "others_busy_during",
            "cpu_pct_min",
            "contended", "bed"]
    f.write(",".join(keys) + "\n")
    for row in rows:
        f.write(",".join(str(row[k]).lower() if isinstance(row[k], bool)
                         else str(row[k]) for k in keys) + "\n")
for p in sorted({r["ranks"] for r in rows}):
    allr = [r for r in rows if r["ranks"] == p]
    rr = [r for r in allr if not r["contended"]] or allr
    med = lambda k: statistics.median(r[k] for r in rr)
    print(json.dumps({"code": "liggghts", "summary": "median", "ranks": p,
                      "runs": len(rr), "runs_contended_excluded": len(allr) - len(rr)
                      if len(rr) < len(allr) else 0,
                      "all_contended": all(r["contended"] for r in rr),
                      "particles": rr[0]["particles"],
                      "steps": rr[0]["steps"], "wall_s": round(med("wall_s"), 4),
                      "particle_steps_per_s": round(med("particle_steps_per_s")),
                      "best_particle_steps_per_s": max(r["particle_steps_per_s"] for r in rr),
                      "peak_rss_mb": round(med("peak_rss_mb"), 1),
                      "peak_rss_total_mb": round(med("peak_rss_total_mb"), 1),
                      "bed": bed, "cpu": cpu}))
print("[run_bench] wrote %s" % csv, file=sys.stderr)
PYEOF

#!/usr/bin/env bash
# What each rolling model costs in the force pass (issue 18): `scoopsim bench step` on one saved
# dig state, run interleaved (A, B, C, D, A, B, ...) as
#   base    a baseline binary (BASE, the code before the contact-law choice) with the state's scene
#   edem    build/scoopsim, the scene's materials under contact_law {rolling_model: edem}
#   cdt     the same with cdt
#   legacy  the same with legacy (and exact_restitution: the old law, bit for bit)
# The figure is the force pass's time (ms_pairs: particle-particle and particle-plane contacts)
# per awake particle-step, in ns: the models move the particles differently, so the awake set
# drifts apart over the run, and the per-particle cost is what the model changes. Prints each
# run's JSON line, then per variant the median and range of that figure and the median and range
# over rounds of its ratio to base's run of the same round, and the same ratio for the whole step
# (edem's 1/|w| is made in the kick, outside the force pass); appends one CSV row per run to
# bench/results/$MACHINE/contact_law_cost.csv.
#
#   BASE=/tmp/scoopsim_base [NEW=build/scoopsim] bench/contact_law_cost.sh [STATE_SCENE] [THREADS]
#     STATE_SCENE default bench/cache/dig_state.yaml (bench/run_dig_step.sh makes it), THREADS 2
# Environment: NRUNS (5), STEPS (300), WARM (20), MACHINE (hostname), QUIET_WAIT (seconds,
# default 0: bench/wait_quiet.sh).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
: "${BASE:?set BASE to the baseline scoopsim binary}"
scene=${1:-$ROOT/bench/cache/dig_state.yaml}
threads=${2:-2}
NRUNS=${NRUNS:-5}
STEPS=${STEPS:-300}
WARM=${WARM:-20}
MACHINE=${MACHINE:-$(hostname -s 2>/dev/null || hostname)}
CSV="$ROOT/bench/results/$MACHINE/contact_law_cost.csv"
mkdir -p "$(dirname "$CSV")"
[ -s "$CSV" ] || echo "date,variant,binary,run,threads,steps,awake_per_step,ms_pairs,ns_pairs_per_awake_particle_step,ms_per_step,state_hash" >"$CSV"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The scene with the repository's materials file, and one copy per model whose materials file
# starts with that contact_law.
sed "s|^materials: .*|materials: $ROOT/scenes/materials.yaml|" "$scene" >"$work/base.yaml"
for model in edem cdt legacy; do
  damping=standard
  [ "$model" = legacy ] && damping=exact_restitution
  { echo "contact_law: {rolling_model: $model, damping: $damping}"
    cat "$ROOT/scenes/materials.yaml"; } >"$work/materials_$model.yaml"
  sed "s|^materials: .*|materials: $work/materials_$model.yaml|" "$scene" >"$work/$model.yaml"
done

. "$ROOT/bench/wait_quiet.sh"
log="$work/log"
for r in $(seq "$NRUNS"); do
  for variant in base edem cdt legacy; do
    bin=${NEW:-$ROOT/build/scoopsim}
    [ "$variant" = base ] && bin=$BASE
    wait_quiet
    line=$("$bin" bench step "$work/$variant.yaml" --warm "$WARM" --steps "$STEPS" \
      --threads "$threads")
    echo "$variant $line" | tee -a "$log"
    /usr/bin/python3 - "$line" "$CSV" "$variant" "$bin" "$r" "$threads" <<'PY'
import datetime, json, sys
line, csv, variant, binary, run, threads = sys.argv[1:]
d = json.loads(line)
ns = d["ms_pairs"] * 1e6 / d["awake_per_step"]
with open(csv, "a") as f:
    f.write(",".join([datetime.datetime.utcnow().isoformat(timespec="seconds"), variant, binary,
                      run, threads, str(d["steps"]), str(d["awake_per_step"]), str(d["ms_pairs"]),
                      f"{ns:.3f}", str(d["ms_per_step"]), d.get("state_hash", "")]) + "\n")
PY
  done
done
/usr/bin/python3 - "$log" <<'PY'
import json, statistics, sys
runs, steps = {}, {}
for l in open(sys.argv[1]):
    v, j = l.split(" ", 1)
    d = json.loads(j)
    runs.setdefault(v, []).append(d["ms_pairs"] * 1e6 / d["awake_per_step"])
    steps.setdefault(v, []).append(d["ms_per_step"] * 1e6 / d["awake_per_step"])
for v, xs in runs.items():
    ratios = [x / b for x, b in zip(xs, runs["base"])]
    step_ratios = [x / b for x, b in zip(steps[v], steps["base"])]
    print(f"{v:7s} ns/awake particle-step median {statistics.median(xs):.1f}"
          f" range {min(xs):.1f}-{max(xs):.1f}"
          f"  ratio to base: median {statistics.median(ratios):.3f}"
          f" range {min(ratios):.3f}-{max(ratios):.3f}"
          f"; whole step: median {statistics.median(step_ratios):.3f}"
          f" range {min(step_ratios):.3f}-{max(step_ratios):.3f}")
PY

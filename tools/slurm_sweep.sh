#!/usr/bin/env bash
# A sweep as a Slurm job array: each array task runs one case (`scoopsim sweep --case I`), so a
# sweep spreads over as many nodes as the queue gives; a resubmitted array skips the cases that are
# done and resumes a stopped one from its last keep (its pour so far or its running pass, kept
# every --checkpoint-every seconds, default 600; sim/studies/sweep.h).
#
#   N=$(build/scoopsim sweep SWEEP.yaml --list | wc -l)      # the number of cases
#   sbatch --array=0-$((N-1)) tools/slurm_sweep.sh SWEEP.yaml OUT_DIR
#   build/scoopsim table build OUT_DIR -o OUT_DIR/table.h5  # once every task has finished
#
# (or, to chain it: sbatch --dependency=afterok:<array job id> --wrap "build/scoopsim table build
# OUT_DIR -o OUT_DIR/table.h5"). Each task gets its --cpus-per-task as DEM threads; SCOOPSIM (default: build/scoopsim beside
# this script's folder) names the binary. A task's exit status is its case's (sim/input/exit_status.h).
#SBATCH --job-name=scoopsim-sweep
#SBATCH --cpus-per-task=4
#SBATCH --time=24:00:00
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: sbatch --array=0-(N-1) $0 SWEEP.yaml OUT_DIR   (N: scoopsim sweep SWEEP.yaml --list | wc -l)" >&2
  exit 2
fi
if [ -z "${SLURM_ARRAY_TASK_ID:-}" ]; then
  echo "$0: not a Slurm array task (SLURM_ARRAY_TASK_ID unset); submit it with sbatch --array" >&2
  exit 2
fi
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SCOOPSIM="${SCOOPSIM:-$here/build/scoopsim}"
export OMP_WAIT_POLICY=PASSIVE
exec "$SCOOPSIM" sweep "$1" -o "$2" --case "$SLURM_ARRAY_TASK_ID" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" --quiet

#!/usr/bin/env bash
# Crash consistency of a run's output, write by write: runs `scoopsim run SCENE` again and again,
# SIGKILLed just before its K-th write to the output (the driver's test hook
# SCOOPSIM_H5_KILL_AT_WRITE, sim/files/h5_clean_driver.cpp) for K = 1, 1 + STEP, ... until a run ends
# unkilled, and reads each killed file with `h5ls -r` (a separate process: HDF5's reader can crash
# on a torn file). A file is unreadable when h5ls fails or a snapshot before the last lacks one of
# its 9 datasets. Prints one CSV row: scene, commit, step, kill points, no file yet (killed before
# the file was put in place), unreadable, and the first K the run outlived (its writes are fewer).
#
#   bench/kill_points.sh SCENE [STEP]        # e.g. a 60-sphere bed, snapshot_every: 1
# (docs/files.md, Crash-safe output; the rows of 2026-12-04 are bench/results/vm/h5_kill_points.csv)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN=${BIN:-$ROOT/build/scoopsim}
SCENE=$1
STEP=${2:-1}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=$work/k.h5
points=0 nofile=0 bad=0 k=1
while :; do
  rm -f "$out"
  if { SCOOPSIM_H5_KILL_AT_WRITE=$k "$BIN" run "$SCENE" -o "$out" --threads 1 -q; } 2>/dev/null; then
    break  # ended before its k-th write
  fi
  points=$((points + 1))
  if [ ! -f "$out" ]; then
    nofile=$((nofile + 1))
  elif ! listing=$(h5ls -r "$out" 2>&1); then
    bad=$((bad + 1))
  else
    groups=$(grep -cE '^/snapshots/[0-9]+ +Group' <<<"$listing" || true)
    sets=$(grep -cE '^/snapshots/[0-9]+/[a-z_]+ +Dataset' <<<"$listing" || true)
    [ "$sets" -ge $((9 * (groups - 1))) ] || bad=$((bad + 1))
  fi
  k=$((k + STEP))
done
echo "$SCENE,$(git -C "$ROOT" rev-parse --short HEAD),$STEP,$points,$nofile,$bad,$k"

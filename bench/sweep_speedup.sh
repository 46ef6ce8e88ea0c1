#!/usr/bin/env bash
# The MPI speedup of a sweep: interleaved pairs of a plain run (one case after another, one DEM
# thread) and `mpirun -np RANKS` (one thread a rank), each into a fresh folder; prints one CSV row
# per run and the median ratio. Usage: bench/sweep_speedup.sh [SWEEP] [PAIRS] [RANKS]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SWEEP="${1:-$here/scenes/sweeps/tiny.yaml}"
PAIRS="${2:-3}"
RANKS="${3:-2}"
BIN="${SCOOPSIM:-$here/build/scoopsim}"
export OMP_WAIT_POLICY=PASSIVE OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
wall() { local t0 t1; t0=$(date +%s.%N); "$@" >/dev/null 2>&1; t1=$(date +%s.%N); echo "$t1 - $t0" | bc; }
echo "machine,sweep,mode,ranks,pair,wall_s"
plain=(); mpi=()
for k in $(seq 1 "$PAIRS"); do
  p=$(wall "$BIN" sweep "$SWEEP" -o "$tmp/plain$k" --threads 1 -q)
  m=$(wall mpirun -np "$RANKS" --oversubscribe "$BIN" sweep "$SWEEP" -o "$tmp/mpi$k" -q)
  echo "$(hostname),$(basename "$SWEEP"),plain,1,$k,$p"
  echo "$(hostname),$(basename "$SWEEP"),mpi,$RANKS,$k,$m"
  plain+=("$p"); mpi+=("$m")
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
mp=$(median "${plain[@]}"); mm=$(median "${mpi[@]}")
echo "# median plain $mp s, mpi $mm s, speedup $(echo "scale=2; $mp / $mm" | bc)" >&2

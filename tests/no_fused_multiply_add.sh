#!/usr/bin/env bash
# The guard of "The same bits on every x86-64 machine" (top-level CMakeLists.txt): no fused
# multiply-add instruction (vfmadd*, vfmsub*, vfnmadd*, vfnmsub*, vfmaddsub*, vfmsubadd*) in the
# libraries that make a run's state (dem, arm, sim), whatever this host's -march=native enables.
# A fused instruction rounds once where the source rounds twice, so a host that has one gives
# other last bits than a host without, and the pinned hashes move. On failure it names each
# function that holds one: add its file to the SCOOPSIM_NO_FUSED_FLAGS list of its folder.
#   tests/no_fused_multiply_add.sh libdem.a libarm.a libsim.a
set -euo pipefail
if [ $# -eq 0 ]; then
  echo "usage: $0 LIBRARY.a ..." >&2
  exit 2
fi
status=0
for lib in "$@"; do
  if [ ! -s "$lib" ]; then
    echo "no_fused_multiply_add: $lib: no such library" >&2
    exit 2
  fi
  # Function headers and fused instructions, then each function that holds one, once.
  found=$(objdump -d -C --no-show-raw-insn "$lib" |
    awk '/^[0-9a-f]+ <.*>:$/ { fn = $0; next }
         $2 ~ /^vfn?m(add|sub)/ { if (!(fn in seen)) { seen[fn] = 1; print fn } count[fn]++ }')
  if [ -n "$found" ]; then
    echo "no_fused_multiply_add: $(basename "$lib"): fused multiply-add in:" >&2
    echo "$found" | sed 's/^/  /' >&2
    status=1
  fi
done
if [ "$status" -eq 0 ]; then echo "no_fused_multiply_add: none in $*"; fi
exit "$status"

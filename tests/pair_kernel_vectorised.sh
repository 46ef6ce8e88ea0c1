#!/usr/bin/env bash
# The guard of the pair kernel's vectorisation (dem/CMakeLists.txt, force_pass.cpp): every
# instance of dem's PairForces (the Hertz-Mindlin batch, the larger part of a dig's step) holds a
# packed square root (sqrtpd on xmm, ymm or zmm), i.e. the compiler ran its loop one contact per
# SIMD lane. Without -fno-trapping-math GCC 12 on a host without AVX-512 left the loop scalar
# ("control flow in loop") and the step 1.4x slower at the same bits (journal section 39). On
# failure it names each instance left scalar.
#   tests/pair_kernel_vectorised.sh libdem.a
set -euo pipefail
if [ $# -ne 1 ] || [ ! -s "$1" ]; then
  echo "usage: $0 LIBDEM.a (an existing library)" >&2
  exit 2
fi
report=$(objdump -d -C --no-show-raw-insn "$1" |
  awk '/^[0-9a-f]+ <.*>:$/ { fn = ($0 ~ /PairForces</) ? $0 : ""; if (fn != "") seen[fn] = 0; next }
       fn != "" && $2 ~ /^v?sqrtpd$/ { seen[fn] = 1 }
       END { n = 0; for (f in seen) { n++; if (!seen[f]) print "scalar: " f }
             if (n == 0) print "none found" }')
if [ -n "$report" ]; then
  echo "pair_kernel_vectorised: $(basename "$1"): PairForces not vectorised:" >&2
  echo "$report" | sed 's/^/  /' >&2
  exit 1
fi
echo "pair_kernel_vectorised: every PairForces instance in $(basename "$1") has packed roots"

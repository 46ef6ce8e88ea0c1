#!/usr/bin/env bash
# How right the progress line's ETA is: runs a scoopsim command under a pseudo-terminal (so the
# live line is rewritten 4 times a second), then for each progress label (bed, dig, run) compares
# elapsed + ETA on every line after the first tenth of that phase with the phase's real wall
# time. Prints the worst and the median relative error and the final percent.
#
#   bench/eta_check.sh run scenes/quick_dig.yaml -o out/quick_dig.h5
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN=${BIN:-$ROOT/build/scoopsim}
tty_log=$(mktemp)
trap 'rm -f "$tty_log"' EXIT
script -q -e -c "$(printf '%q ' "$BIN" "$@")" "$tty_log" >/dev/null
/usr/bin/python3 - "$tty_log" <<'PY'
import re, statistics, sys
text = open(sys.argv[1], errors="replace").read().replace("\x1b[K", "")
pat = re.compile(r"^(\w+)\s+([\d.]+)%.*elapsed ([\d:]+)\s+ETA ([\d:-]+)")
def secs(c):
    if "-" in c: return None
    s = 0
    for part in c.split(":"): s = 60 * s + int(part)
    return s
phases = {}
for piece in re.split(r"[\r\n]", text):
    m = pat.match(piece.strip())
    if m: phases.setdefault(m.group(1), []).append((float(m.group(2)), secs(m.group(3)), secs(m.group(4))))
for label, rows in phases.items():
    total = rows[-1][1]
    errs = [(e + eta) / total - 1 for pct, e, eta in rows[:-1]
            if eta is not None and total > 0 and e >= 0.1 * total]
    if not errs:
        print(f"{label}: {total} s, final {rows[-1][0]}%, too short to judge the ETA"); continue
    worst = max(errs, key=abs)
    print(f"{label}: {total} s wall, final {rows[-1][0]:.1f}%; predicted total after the first "
          f"tenth: median error {100*statistics.median(errs):+.0f}%, worst {100*worst:+.0f}% "
          f"({len(errs)} lines)")
PY

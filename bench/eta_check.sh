#!/usr/bin/env bash
# How right the progress line's ETA is: runs a scoopsim command under a pseudo-terminal (so the
# live line is rewritten 4 times a second), then for each progress label (bed, dig, run) compares
# elapsed + ETA on every line after the first tenth of that phase with the phase's real wall
# time. Prints the worst and the median relative error and the final percent.
#
#   bench/eta_check.sh run scenes/quick_dig.yaml -o out/quick_dig.h5
#   KEEP=/tmp/x bench/eta_check.sh ...     # also keeps /tmp/x.tty and /tmp/x.timing
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN=${BIN:-$ROOT/build/scoopsim}
tty_log=$(mktemp)
timing=$(mktemp)
trap '[ -n "${KEEP:-}" ] && cp "$tty_log" "$KEEP.tty" && cp "$timing" "$KEEP.timing"; rm -f "$tty_log" "$timing"' EXIT
script -q -e -T "$timing" -c "$(printf '%q ' "$BIN" "$@")" "$tty_log" >/dev/null
/usr/bin/python3 - "$tty_log" "$timing" <<'PY'
import re, statistics, sys
# The wall time of every byte, from script's timing file (delay before each chunk, its size),
# so each progress line gets the time it was printed to the millisecond.
raw = open(sys.argv[1], "rb").read()
start = raw.index(b"\n") + 1 if raw.startswith(b"Script started") else 0
clock, offset, stamps = 0.0, start, []
for line in open(sys.argv[2]):
    delay, size = line.split()[:2]
    clock += float(delay)
    stamps.append((offset, clock))
    offset += int(size)
def time_at(pos):
    t = 0.0
    for off, c in stamps:
        if off > pos: break
        t = c
    return t
text = raw.decode(errors="replace").replace("\x1b[K", "")
pat = re.compile(r"^(\w+)\s+([\d.]+)%.*elapsed ([\d:]+)\s+ETA (?:<= )?([\d:-]+)")
def secs(c):
    if "-" in c: return None
    s = 0
    for part in c.split(":"): s = 60 * s + int(part)
    return s
phases = {}
pos = 0
for piece in re.split(r"([\r\n])", text):
    m = pat.match(piece.strip())
    if m:
        phases.setdefault(m.group(1), []).append(
            (float(m.group(2)), time_at(len(text[:pos].encode())), secs(m.group(4))))
    pos += len(piece)
for label, rows in phases.items():
    # Wall times from the phase's first line (printed 0.25 s or less after it began).
    t0 = rows[0][1]
    rows = [(pct, t - t0, eta) for pct, t, eta in rows]
    total = rows[-1][1]
    errs = [(e + eta) / total - 1 for pct, e, eta in rows[:-1]
            if eta is not None and total > 0 and e >= 0.1 * total]
    if not errs:
        print(f"{label}: {total:.1f} s, final {rows[-1][0]}%, too short to judge the ETA"); continue
    worst = max(errs, key=abs)
    print(f"{label}: {total:.1f} s wall, final {rows[-1][0]:.1f}%; predicted total after the first "
          f"tenth: median error {100*statistics.median(errs):+.0f}%, worst {100*worst:+.0f}% "
          f"({len(errs)} lines)")
PY

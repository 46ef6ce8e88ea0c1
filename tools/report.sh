#!/bin/bash
# The report of the study's analyses: the figures that come from other files, then the page.
#   tools/report.sh DIR [REPORT.html]        (default DIR/report.html)
# DIR's layout is tools/report.py's (--help): the studies write into it (each section of the page
# shows its command); this script runs only the cheap steps after them:
#   DIR/shape/shape.h5 -> DIR/shape/shape_force.png      tools/plot_wrench.py --force-only
#   DIR/lookup/table.h5 -> DIR/lookup/lookup_fig*.png, lookup_trends.csv   tools/plot_lookup.py
# (each remade when missing or older than its input), then tools/report.py DIR -o REPORT.html.
# A study not run is a "not run" section of the page, not a failure; a step that fails stops here.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: tools/report.sh DIR [REPORT.html]" >&2
  exit 2
fi
dir=$1
out=${2:-$dir/report.html}
py=${SCOOPSIM_PYTHON:-python3}  # any Python with numpy, h5py and matplotlib
stale() {  # stale IN OUT...: an OUT is missing or older than IN
  local in=$1 out
  shift
  for out in "$@"; do
    if [ ! -f "$out" ] || [ "$in" -nt "$out" ]; then return 0; fi
  done
  return 1
}
if [ -f "$dir/shape/shape.h5" ] && stale "$dir/shape/shape.h5" "$dir/shape/shape_force.png"; then
  "$py" tools/plot_wrench.py "$dir/shape/shape.h5" --force-only -o "$dir/shape/shape_force.png"
fi
lookup=$dir/lookup
if [ -f "$lookup/table.h5" ] && stale "$lookup/table.h5" "$lookup/lookup_trends.csv" \
  "$lookup/lookup_fig9.png" "$lookup/lookup_fig10.png" "$lookup/lookup_fig11.png"; then
  "$py" tools/plot_lookup.py "$lookup/table.h5" -o "$lookup"
fi
"$py" tools/report.py "$dir" -o "$out"

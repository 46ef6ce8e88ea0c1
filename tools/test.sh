#!/usr/bin/env bash
# Installs the dependencies, builds everything and runs the tests. Exit status: ctest's.
#   tools/test.sh            release build in build/, every test (~5 min on a quiet 2-core machine)
#   tools/test.sh --quick    the same build, every test but the `slow` ones (tests/slow_tests.txt,
#                            each over ~5 s): under 2 minutes, for the edit-build-test loop
#   CI=true tools/test.sh    the `ci` preset (warnings as errors)
#   tools/test.sh --help     this text
set -euo pipefail
cd "$(dirname "$0")/.."

quick=false
case "${1:-}" in
  "") ;;
  --quick) quick=true ;;
  -h | --help)
    sed -n '2,7s/^# \{0,1\}//p' "$0"
    exit 0
    ;;
  *)
    echo "tools/test.sh: unknown option $1 (expected --quick or --help)" >&2
    exit 2
    ;;
esac

bash tools/install-deps.sh --test  # --test: chromium for the report's render check

preset=release
if [ "${CI:-}" = "true" ]; then preset=ci; fi
jobs=$(nproc)

cmake --preset "$preset" -DSCOOPSIM_TESTS=ON  # ON even where build/ was configured without them
cmake --build build -j"$jobs"

# ctest runs nproc tests at once and each may start nproc OpenMP threads: with the default
# spinning barriers an oversubscribed run slows down tens of times, so waiting threads sleep.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"

select=()
if $quick; then select=(-LE slow); fi
status=0
ctest --test-dir build --output-on-failure -j"$jobs" "${select[@]}" || status=$?
exit "$status"

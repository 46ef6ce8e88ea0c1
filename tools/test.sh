#!/usr/bin/env bash
# Installs the dependencies, builds everything and runs every test. Exit status: ctest's.
#   tools/test.sh            release build in build/
#   CI=true tools/test.sh    the `ci` preset (warnings as errors)
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh --test  # --test: chromium for the report's render check

preset=release
if [ "${CI:-}" = "true" ]; then preset=ci; fi
jobs=$(nproc)

cmake --preset "$preset"
cmake --build build -j"$jobs"

# ctest runs nproc tests at once and each may start nproc OpenMP threads: with the default
# spinning barriers an oversubscribed run slows down tens of times, so waiting threads sleep.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"

status=0
ctest --test-dir build --output-on-failure -j"$jobs" || status=$?
exit "$status"

#!/usr/bin/env bash
# ctest package.tests_off_build (label slow): the project configured and built with
# -DSCOOPSIM_TESTS=OFF and GoogleTest made unfindable (-DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON),
# in a temporary build folder: every library and the CLI build, GoogleTest is never looked for
# (no GTest_DIR in the cache), and the binary runs (--version). A second full build: ccache, when
# there is one, makes its compiles hits of the main build's (same compiler and flags). The folder
# is BUILD_DIR-tests-off.XXXXXX beside BUILD_DIR, so that a ccache base_dir that rewrites paths
# relative to the compiler's folder finds the same relative paths as in BUILD_DIR.
#   tests/package/tests_off_build.sh BUILD_DIR C_COMPILER CXX_COMPILER BUILD_TYPE [-DOPTION=...]
# The options given after BUILD_TYPE are the main build's own (tests/CMakeLists.txt passes
# SCOOPSIM_NATIVE, _PORTABLE_ISA, _WERROR and _SANITIZE), so that the compile lines are the same.
set -euo pipefail
main_build=$(cd "$1" && pwd)
cc=$2
cxx=$3
build_type=$4
shift 4
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d "$main_build-tests-off.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() {
  echo "package.tests_off_build: $*" >&2
  exit 1
}
launcher=()
how="no ccache"
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  how=ccache
fi
start=$(date +%s)
cmake -S "$source_dir" -B "$tmp" -DSCOOPSIM_TESTS=OFF -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON \
  -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE="$build_type" \
  "${launcher[@]}" "$@" >"$tmp/configure.log" 2>&1 || {
  cat "$tmp/configure.log" >&2
  fail "configure failed"
}
if grep -q '^GTest_DIR' "$tmp/CMakeCache.txt"; then fail "GoogleTest was looked for"; fi
cmake --build "$tmp" -j2 >"$tmp/build.log" 2>&1 || {
  tail -50 "$tmp/build.log" >&2
  fail "build failed"
}
[ ! -e "$tmp/tests" ] || fail "tests/ was configured"
version=$("$tmp/scoopsim" --version) || fail "scoopsim --version failed"
echo "package.tests_off_build: configured and built in $(($(date +%s) - start)) s ($how): $version"

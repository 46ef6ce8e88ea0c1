#!/usr/bin/env bash
# ctest package.install (label slow): `cmake --install` into a temporary prefix, then a user's
# project (tests/package/CMakeLists.txt) built against it with find_package(scoopsim):
#   1. the prefix holds the binary, the static libraries, the public headers (no internal ones),
#      the package config and share/scoopsim's scenes, assets and scripts, and no installed CMake
#      file names the source or build tree;
#   2. COMPONENTS dem with Eigen3, PkgConfig, yaml-cpp, HDF5, assimp and MPI made unfindable
#      (CMAKE_DISABLE_FIND_PACKAGE_*): dem_free_fall, linking scoopsim::dem alone, matches the
#      closed form of free fall (dem_free_fall.cpp);
#   3. COMPONENTS arm with OpenMP, yaml-cpp, HDF5, assimp and MPI made unfindable: arm_hold,
#      linking scoopsim::arm alone, loads the installed URDF (dof 6) and holds it with the
#      gravity torques (arm_hold.cpp);
#   4. every part: sim_scene, linking scoopsim::sim and including every installed header, loads
#      the installed quick_dig scene (sim_scene.cpp);
#   5. the installed binary checks an installed scene, and an installed script runs under PYTHON.
#   tests/package/install_test.sh BUILD_DIR CXX_COMPILER PYTHON [LIBDIR]
# LIBDIR: CMAKE_INSTALL_LIBDIR (lib unless the build was configured for a prefix such as /usr).
# Exit 0 when all hold; otherwise the first failure is named on stderr.
set -euo pipefail
build=$(cd "$1" && pwd)
cxx=$2
python=$3
lib=${4:-lib}
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/scoopsim_install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
fail() {
  echo "package.install: $*" >&2
  exit 1
}

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" || {
  cat "$tmp/install.log" >&2
  fail "cmake --install failed"
}

# 1. The tree.
for f in bin/scoopsim $lib/libdem.a $lib/libarm.a $lib/libsim_input.a $lib/libsim_files.a \
  $lib/libsim_loop.a $lib/libsim_studies.a $lib/cmake/scoopsim/scoopsimConfig.cmake \
  $lib/cmake/scoopsim/scoopsimConfigVersion.cmake $lib/cmake/scoopsim/scoopsim-dem-targets.cmake \
  include/scoopsim/dem/system.h include/scoopsim/arm/bullet_arm.h \
  include/scoopsim/sim/input/scene.h include/scoopsim/sim/loop/world.h \
  include/scoopsim/sim/studies/commands.h share/scoopsim/assets/lander_arm.urdf \
  share/scoopsim/assets/scoop.stl share/scoopsim/assets/lookup_coarse.csv \
  share/scoopsim/scenes/quick_dig.yaml share/scoopsim/scenes/materials.yaml \
  share/scoopsim/tools/study_csv.py; do
  [ -f "$prefix/$f" ] || fail "missing $f"
done
for f in bin/scoopsim share/scoopsim/tools/plot_wrench.py share/scoopsim/tools/report.py \
  share/scoopsim/tools/report.sh; do
  [ -x "$prefix/$f" ] || fail "not executable: $f"
done
internal=$(find "$prefix/include" -name 'internal_*.h' -o -name yaml_input.h)
[ -z "$internal" ] || fail "internal headers installed: $internal"
if grep -rl -e "$source_dir" -e "$build" "$prefix/$lib/cmake"; then
  fail "an installed CMake file names the source or build tree (above)"
fi
echo "package.install: $(find "$prefix" -type f | wc -l) files, $(du -sh "$prefix" | cut -f1):" \
  "$(find "$prefix/include" -name '*.h' | wc -l) headers," \
  "$(find "$prefix/share/scoopsim/scenes" -name '*.yaml' | wc -l) scenes"

# 2-4. A user's project, once per part.
user() {  # user PART [cmake options...]: configure and build tests/package as PART
  local part=$1
  shift
  cmake -S "$here" -B "$tmp/user_$part" -DCMAKE_PREFIX_PATH="$prefix" -DPART="$part" \
    -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Release "$@" >"$tmp/$part.log" 2>&1 &&
    cmake --build "$tmp/user_$part" -j2 >>"$tmp/$part.log" 2>&1 || {
    cat "$tmp/$part.log" >&2
    fail "the user's project for $part failed to configure or build (above)"
  }
}
no() {  # no PKG...: -DCMAKE_DISABLE_FIND_PACKAGE_PKG=ON for each
  local p
  for p in "$@"; do printf -- '-DCMAKE_DISABLE_FIND_PACKAGE_%s=ON\n' "$p"; done
}
mapfile -t not_dem < <(no Eigen3 PkgConfig yaml-cpp HDF5 assimp MPI)
mapfile -t not_arm < <(no OpenMP yaml-cpp HDF5 assimp MPI)
user dem "${not_dem[@]}"
OMP_NUM_THREADS=1 "$tmp/user_dem/dem_free_fall" || fail "dem_free_fall failed"
user arm "${not_arm[@]}"
"$tmp/user_arm/arm_hold" || fail "arm_hold failed"
user all
grep -o "scoopsim headers in .*" "$tmp/all.log"
"$tmp/user_all/sim_scene" || fail "sim_scene failed"

# 5. The installed binary on an installed scene (its materials and mesh found in share/), and a
# script under the given Python (study_csv.py imported beside it).
"$prefix/bin/scoopsim" check "$prefix/share/scoopsim/scenes/quick_dig.yaml" >"$tmp/check.log" \
  2>&1 || {
  cat "$tmp/check.log" >&2
  fail "scoopsim check on the installed quick_dig.yaml failed"
}
"$python" "$prefix/share/scoopsim/tools/plot_balovnev.py" --help >/dev/null ||
  fail "share/scoopsim/tools/plot_balovnev.py --help failed under $python"
echo "package.install: ok"

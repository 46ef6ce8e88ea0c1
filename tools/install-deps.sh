#!/usr/bin/env bash
# Installs every Debian package scoopsim needs. Idempotent; runs as root or through sudo.
#   tools/install-deps.sh          what building, running and plotting need
#   tools/install-deps.sh --test   also what only the tests need (chromium: tools/report.py's page
#                                  is checked in a headless browser; pytest for the Python
#                                  module's tests); tools/test.sh passes it
# The Python module needs pybind11-dev and python3-dev; runs as ROS bags need python3-rosbag and
# the message packages (ROS 1 Noetic's, as Debian 12 ships them).
set -euo pipefail
PKGS=(
  build-essential cmake pkg-config git
  libyaml-cpp-dev libcli11-dev libhdf5-dev hdf5-tools zlib1g-dev libassimp-dev
  libgtest-dev googletest
  python3 python3-numpy python3-h5py python3-matplotlib
  openmpi-bin libopenmpi-dev
  libosmesa6-dev libgl-dev libpng-dev
  libbullet-dev liburdfdom-dev libeigen3-dev
  pybind11-dev python3-dev
  python3-rosbag python3-std-msgs python3-sensor-msgs python3-geometry-msgs python3-tf2-msgs
)
case "${1:-}" in
  --test) PKGS+=(chromium python3-pytest) ;;
  "") ;;
  *) echo "install-deps: unknown argument $1 (expected --test or nothing)" >&2; exit 2 ;;
esac
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

#!/usr/bin/env bash
# Installs what the peer benchmarks need beyond scoopsim's own packages (tools/install-deps.sh):
# LIGGGHTS 3.8 for bench/liggghts/ and bench/compare_liggghts.sh, GNU time for their memory
# figures and python3-yaml for h5_to_liggghts.py. Not needed to build, test or run scoopsim.
# Idempotent; runs as root or through sudo.
set -euo pipefail
PKGS=(liggghts time python3-yaml)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && { echo "install-peers: all ${#PKGS[@]} packages present"; exit 0; }
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

#!/usr/bin/env bash
# Installs the Debian 12 packages csw needs, only when some are missing.
# Usage: scripts/install-deps.sh [--gui] [--all]   (run as root)
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libceres-dev libopencv-dev
  libhdf5-dev hdf5-tools libdeflate-dev python3-h5py
  libespeak-ng-dev espeak-ng-data libsndfile1-dev sox
  nlohmann-json3-dev libssl-dev libpugixml-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  qt6-base-dev qt6-base-dev-tools qt6-svg-dev qt6-multimedia-dev
  libqcustomplot-dev libqcustomplot2.1-qt6 libgl-dev
  clang libclang-rt-14-dev clang-format
  praat xvfb
  chromium
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages and not root; run: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"

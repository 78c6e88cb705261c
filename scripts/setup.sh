#!/usr/bin/env bash
# Shared set-up of scripts/demo.sh and scripts/test.sh: installs the Debian packages netlab needs
# (only those missing), then configures and builds with CMake into build/ (or $NETLAB_BUILD_DIR).
# Source it; it defines NETLAB_ROOT and NETLAB_BUILD_DIR. A script that needs more packages names
# them in the array netlab_extra_packages before it sources this.
set -euo pipefail

NETLAB_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
NETLAB_BUILD_DIR=${NETLAB_BUILD_DIR:-"$NETLAB_ROOT/build"}
NETLAB_BUILD_TYPE=${NETLAB_BUILD_TYPE:-Release}
[ -v netlab_extra_packages ] || netlab_extra_packages=()

netlab_packages=(
  g++ cmake make pkg-config
  libeigen3-dev libyaml-cpp-dev libhdf5-dev libgtest-dev
  libceres-dev libopencv-dev libopencv-contrib-dev qt6-base-dev
  hdf5-tools python3 fonts-dejavu-core
  libopenmpi-dev openmpi-bin
  "${netlab_extra_packages[@]}"
)

netlab_install_missing() {
  local missing=()
  for p in "${netlab_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "netlab: installing missing packages: ${missing[*]}" >&2
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "netlab: need root (or sudo) to apt-get install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

netlab_build() {
  cmake -S "$NETLAB_ROOT" -B "$NETLAB_BUILD_DIR" -DCMAKE_BUILD_TYPE="$NETLAB_BUILD_TYPE" "$@" >/dev/null
  cmake --build "$NETLAB_BUILD_DIR" -j2
}

netlab_install_missing

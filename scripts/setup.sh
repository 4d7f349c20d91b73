#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# Installs what is missing (Debian 12 packages), then configures and builds
# HMC into build/. Sourced by scripts/demo.sh, scripts/test.sh and (with
# HMC_SETUP_NO_BUILD=1: install only) scripts/sanitize.sh; safe to run again
# (it only installs and rebuilds what is needed).
set -eu

HMC_ROOT=$(cd "$(dirname "$0")/.." && pwd)
HMC_BUILD=${HMC_BUILD:-$HMC_ROOT/build}
HMC_PACKAGES="g++ cmake ninja-build pkg-config libtet1.5-dev zlib1g-dev libeigen3-dev doctest-dev python3"

# hmc_install_missing PACKAGE...: installs those of the Debian packages
# that are missing (as root, or with sudo). Returns non-zero if it cannot.
# Also used by scripts/sanitize.sh (with HMC_SETUP_NO_BUILD=1).
hmc_install_missing() {
  missing=""
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
  [ -n "$missing" ] || return 0
  echo "setup: installing$missing"
  if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: need root (or sudo) to install:$missing" >&2; return 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq || return 1
  # shellcheck disable=SC2086
  $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null || return 1
}

# shellcheck disable=SC2086
hmc_install_missing $HMC_PACKAGES || exit 1

JOBS=$(nproc 2>/dev/null || echo 2)
if [ "${HMC_SETUP_NO_BUILD:-0}" != 1 ]; then
  if [ ! -f "$HMC_BUILD/build.ninja" ]; then
    cmake -S "$HMC_ROOT" -B "$HMC_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  fi
  cmake --build "$HMC_BUILD" -j "$JOBS"
fi

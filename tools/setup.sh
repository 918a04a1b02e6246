#!/usr/bin/env bash
# Installs the Debian packages limber needs (only the missing ones), then configures and builds.
#
#   tools/setup.sh [--portable] [--debug]
#
#   --portable   build for baseline x86-64 instead of -march=native
#   --debug      Debug build instead of Release
#
# Environment: LIMBER_BUILD_DIR (default: build), LIMBER_SKIP_INSTALL=1 to skip apt-get.
set -euo pipefail
cd "$(dirname "$0")/.."

native=ON
build_type=Release
for arg in "$@"; do
  case "$arg" in
    --portable) native=OFF ;;
    --debug) build_type=Debug ;;
    *) echo "setup.sh: unknown option '$arg' (expected --portable or --debug)" >&2; exit 2 ;;
  esac
done
build_dir=${LIMBER_BUILD_DIR:-build}

# Build tools and libraries, as Debian 12 packages.
packages=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libtbb-dev libxsimd-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev
  libmujoco-dev libbullet-dev libode-dev
  python3-matplotlib  # tools/plot_*.py, which draw bench/figures/
)

if [ "${LIMBER_SKIP_INSTALL:-0}" != 1 ]; then
  missing=()
  for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
      missing+=("$p")
    fi
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup.sh: installing ${missing[*]}"
    sudo_cmd=()
    if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
fi

# Configure once (or again when the options change), then build.
cmake -S . -B "$build_dir" -G Ninja \
  -DCMAKE_BUILD_TYPE="$build_type" -DLIMBER_NATIVE="$native" >/dev/null
cmake --build "$build_dir" -j2

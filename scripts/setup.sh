#!/usr/bin/env bash
# Installs the Debian packages treelobes needs (only those missing), configures and builds.
# Idempotent: a second run installs nothing and rebuilds only what changed.
# Usage: scripts/setup.sh            (build dir: ./build, binary: build/bin/treelobes)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libboost-dev libpcl-dev libcgal-dev libgmp-dev libmpfr-dev libflann-dev libopenmesh-dev
  libembree-dev libtbb-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libpng-dev zlib1g-dev libgtest-dev libgmock-dev libbenchmark-dev libxgboost-dev
  libbz2-dev liblzma-dev libzstd-dev libbrotli-dev
  parallel slurm-wlm munge
)

missing=()
for package in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

BUILD_DIR=${TREELOBES_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"

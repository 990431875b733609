#!/usr/bin/env bash
# Installs the Debian packages treelobes needs (only those missing), configures and builds.
# Idempotent: a second run installs nothing and rebuilds only what changed.
# Usage: scripts/setup.sh            (build dir: ./build, binary: build/bin/treelobes)
#        scripts/setup.sh --hardening-tools   only the compilers and runtimes of the sanitizer
#                                             and fuzz builds (scripts/sanitize.sh, scripts/fuzz.sh)
# Also installs the npm validators of the export tests under tools/validators (npm ci).
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libboost-dev libpcl-dev libcgal-dev libgmp-dev libmpfr-dev libflann-dev libopenmesh-dev
  libembree-dev libtbb-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libproj-dev libpng-dev zlib1g-dev libgtest-dev libgmock-dev libbenchmark-dev libxgboost-dev
  libbz2-dev liblzma-dev libzstd-dev libbrotli-dev liblzf-dev
  parallel slurm-wlm munge
)

# clang with its sanitizer runtimes and libFuzzer: only the hardening builds use them;
# clang-format-14 checks the house style (.clang-format).
HARDENING_PACKAGES=(clang libclang-rt-14-dev libfuzzer-14-dev clang-format-14)

install_missing() {
  local missing=()
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}" >&2
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

if [ "${1:-}" = "--hardening-tools" ]; then
  install_missing "${HARDENING_PACKAGES[@]}"
  exit 0
fi
install_missing "${PACKAGES[@]}"

# The official validators the export tests run (Khronos glTF-Validator, ajv for the CityJSON
# schemas): npm packages pinned by tools/validators/package-lock.json, installed in that folder.
command -v npm >/dev/null 2>&1 || install_missing nodejs npm
if command -v npm >/dev/null 2>&1; then
  if [ ! -f tools/validators/node_modules/.package-lock.json ] ||
     [ tools/validators/package-lock.json -nt tools/validators/node_modules/.package-lock.json ]; then
    echo "setup: installing the export validators (npm ci in tools/validators)" >&2
    (cd tools/validators && npm ci --no-audit --no-fund --loglevel=error)
  fi
else
  echo "setup: npm not found: the glTF/CityJSON validator tests will fail until node and npm are installed" >&2
fi

BUILD_DIR=${TREELOBES_BUILD_DIR:-build}
# Warnings are errors here (demo, tests and CI all build through this script): the compiler is
# Debian 12's GCC 12 installed above, so any warning is a defect of ours. A hand-made build with
# another compiler keeps the default TREELOBES_WERROR=OFF.
# A unity build (CMake compiles each folder's sources in batches of 8 as one file): Eigen, CLI11 and
# the JSON library are parsed and instantiated once a batch, not once a file, which makes a build
# from scratch about twice as fast.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTREELOBES_WERROR=ON -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"

#!/usr/bin/env bash
# Everything CI proves on every commit (.ci/run calls exactly this), in three steps:
#   1. set-up (scripts/setup.sh), the Release build and the whole suite: unit tests and the
#      end-to-end tests on the real scans in ../shared/data (label `real`; TREELOBES_REAL_DATA)
#   2. the sanitizers (scripts/sanitize.sh): the unit tests but the three SurveyBuffer ones under ASan + UBSan
#      (build-san), the tests of the parallel code under TSan (build-tsan)
#   3. every fuzz target for TREELOBES_FUZZ_SECONDS (default 20) seconds (ctest -L fuzz in
#      build-san)
# TREELOBES_HARDENING=0 stops after step 1 (a quicker local run), TREELOBES_FUZZ_STEP=0 after step 2.
set -euo pipefail
cd "$(dirname "$0")/.."
step() { echo "test.sh: $1 ($(date -u +%H:%M:%S), ${SECONDS}s so far)" >&2; }

step "1/3 build and whole suite"
scripts/setup.sh
export TREELOBES_REAL_DATA=${TREELOBES_REAL_DATA:-$(cd .. && pwd)/shared/data}
ctest --test-dir "${TREELOBES_BUILD_DIR:-build}" --output-on-failure -j "$(nproc)" --timeout 900
[ "${TREELOBES_HARDENING:-1}" = 1 ] || exit 0

step "2/3 sanitizers"
scripts/setup.sh --hardening-tools
scripts/sanitize.sh asan
scripts/sanitize.sh tsan

[ "${TREELOBES_FUZZ_STEP:-1}" = 1 ] || exit 0
step "3/3 fuzz targets"
source scripts/sanitizer_build.sh
cmake "$SAN_BUILD_DIR" -DTREELOBES_FUZZ_SECONDS="${TREELOBES_FUZZ_SECONDS:-20}" >/dev/null
ctest --test-dir "$SAN_BUILD_DIR" -L fuzz --output-on-failure -j "$(nproc)"
step "done"

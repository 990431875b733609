#!/usr/bin/env bash
# Set-up (scripts/setup.sh) followed by the whole test suite: unit tests and the end-to-end
# tests on the real scans in ../shared/data (label `real`; folder from TREELOBES_REAL_DATA).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
export TREELOBES_REAL_DATA=${TREELOBES_REAL_DATA:-$(cd .. && pwd)/shared/data}
ctest --test-dir "${TREELOBES_BUILD_DIR:-build}" --output-on-failure -j "$(nproc)" --timeout 900

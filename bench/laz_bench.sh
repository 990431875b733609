#!/usr/bin/env bash
# LAZ decoding speed (docs/laz.md): points per second on laz/laspy/autzen_trim.laz (format 3,
# 110,000 points, 3 chunks) and laz/pine_plot.laz (format 0) with one and two threads, and full
# versus selective decoding of the layered LAS 1.4 files (COPC format 7, format 6).
# When node and the laz-perf npm package are installed under bench/node_modules, the same files
# are also decoded with laz-perf for a side-by-side figure.
# Usage: bench/laz_bench.sh [BUILD_DIR]   (default: build; data from $TREELOBES_REAL_DATA or ../shared/data)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
data=${TREELOBES_REAL_DATA:-$here/../shared/data}
"$build/bin/bench_laz_decode" "$data"
if command -v node > /dev/null && [ -d "$here/bench/node_modules/laz-perf" ]; then
  echo
  echo "laz-perf (WebAssembly), 1 thread:"
  for f in laz/laspy/autzen_trim.laz laz/pine_plot.laz; do
    node "$here/bench/laz_perf_decode.mjs" "$data/$f"
  done
else
  echo
  echo "laz-perf comparison skipped: needs node and 'npm install --prefix bench laz-perf'"
fi

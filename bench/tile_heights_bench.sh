#!/usr/bin/env bash
# Airborne per-tree measures of `treelobes tile` against the synthetic truth (docs/tile.md,
# "A trimmed crown centre"): for each tile, `tile --mode als` measuring every tree without
# modelling it, then bench/tile_accuracy.py (true trees taller than 5 m matched to found trees
# by points and by the nearest stem within 2 m): height RMSE and bias, stem position RMS, the
# error of the ground at the stem; a last line pools all the tiles' trees.
# Usage: bench/tile_heights_bench.sh [TILE_DIR...]   Each TILE_DIR holds the tile.las and
# truth.csv of `treelobes synth tile`. Default: the eight airborne tiles without competition of
# bench/segment_bench.sh (run it first), open seeds 11-14 and crowded seeds 1-4, in
# /tmp/treelobes_segment_bench. Held-out tiles are made the same way with other seeds:
#   treelobes synth tile --out DIR --seed S --slope 20 --roughness 1 --spacing 1.0 --scanner als \
#       --trees 25 --size 100          (open; crowded: --trees 30 --size 80)
# Environment: TREELOBES_BIN (default build/bin/treelobes), OUT (default
# /tmp/treelobes_tile_heights_bench: one run directory per tile).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
OUT=${OUT:-/tmp/treelobes_tile_heights_bench}
[[ -x "$BIN" ]] || { echo "tile_heights_bench: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
if [[ $# -eq 0 ]]; then
  W=/tmp/treelobes_segment_bench
  set -- "$W"/als_open_1{1,2,3,4} "$W"/als_crowded_{1,2,3,4}
fi
pairs=()
for dir in "$@"; do
  [[ -f "$dir/tile.las" && -f "$dir/truth.csv" ]] || { echo "tile_heights_bench: $dir lacks tile.las or truth.csv" >&2; exit 1; }
  run="$OUT/$(basename "$dir")"
  rm -rf "$run"
  "$BIN" --log-level error tile "$dir/tile.las" --mode als --min-tree-points 100000000 --map-size 200 --out "$run" >/dev/null
  "$BIN" --log-level error convert "$run/points.las" --out "$run/points.csv" >/dev/null
  pairs+=("$dir/truth.csv" "$run")
done
python3 bench/tile_accuracy.py "${pairs[@]}"

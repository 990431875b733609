#!/usr/bin/env bash
# `treelobes tile` figures (docs/tile.md), all from whole-process runs of the CLI:
#   1. a scaling table on synthetic airborne tiles of about 0.25M, 1M and 4M points: wall time,
#      CPU time and peak memory (/usr/bin/time -v), trees found and modelled;
#   2. a synthetic terrestrial plot of about 1.5M points: the same figures;
#   3. accuracy against the synthetic truth (truth.csv): each true tree is matched to the found
#      tree that shares at least half of its points both ways (the issue's rule), and, as before,
#      to the found stem base nearest within 2 m (one-to-one, nearest first); height RMSE and stem
#      position RMS over the matched trees (ALS and TLS) and DBH RMSE over the TLS trees whose DBH
#      quality is ok or partial_arc, with the truth trees taller than 5 m;
#   4. DBH per tree on the real TLS plot treels/pine_plot.las.
# Tiles are synthetic (`treelobes synth tile`): the tile side is chosen from a small calibration
# tile so that the point count comes near the target, with one tree per TREE_AREA m^2.
# Usage: bench/tile_bench.sh [OUT_DIR]   (default /tmp/treelobes_tile_bench)
# Environment: TREELOBES_BIN (default build/bin/treelobes), TREELOBES_REAL_DATA (default
# ../shared/data), ALS_SIZES (default "250000 1000000 4000000"), TLS_POINTS (default 1500000),
# THREADS (default 0 = all), MODE_FLAGS (default empty: fresh segmentation; e.g.
# "--use-input-segmentation" scores the per-tree stages on the true segmentation).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
DATA=${TREELOBES_REAL_DATA:-../shared/data}
OUT=${1:-/tmp/treelobes_tile_bench}
ALS_SIZES=${ALS_SIZES:-"250000 1000000 4000000"}
TLS_POINTS=${TLS_POINTS:-1500000}
THREADS=${THREADS:-0}
TREE_AREA=${TREE_AREA:-60}
MODE_FLAGS=${MODE_FLAGS:-}
[[ -x "$BIN" ]] || { echo "tile_bench: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
[[ -x /usr/bin/time ]] || { echo "tile_bench: /usr/bin/time missing (apt-get install time)" >&2; exit 1; }
mkdir -p "$OUT"
export SOURCE_DATE_EPOCH=${SOURCE_DATE_EPOCH:-1735689600}

ALS_FLAGS=(--pulse-density 10 --max-leaves 4000 --slope 10 --roughness 0.5)
TLS_FLAGS=(--scanner tls --angular-step 0.3 --station-spacing 15 --max-leaves 4000 --slope 5)

# summary_value DIR KEY...: a value of a synthetic tile's summary.json.
summary_value() {
  local dir=$1
  shift
  python3 -c 'import json, sys; d = json.load(open(sys.argv[1]))
for k in sys.argv[2:]: d = d[k]
print(d)' "$dir/summary.json" "$@"
}

# synth_tile NAME TARGET_POINTS FLAGS...: a tile whose side gives about TARGET_POINTS points,
# scaled from a 30 m calibration tile of the same kind.
synth_tile() {
  local name=$1 target=$2
  shift 2
  local calibration="$OUT/calibration_$name"
  if [[ ! -f "$calibration/tile.las" ]]; then
    "$BIN" --log-level error synth tile --trees 15 --size 30 --seed 3 "$@" --out "$calibration" >/dev/null
  fi
  local density
  density=$(summary_value "$calibration" points_per_m2)
  local side trees
  side=$(python3 -c "import math; print(round(math.sqrt($target / $density), 1))")
  trees=$(python3 -c "print(max(1, int($side * $side / $TREE_AREA)))")
  if [[ ! -f "$OUT/$name/tile.las" ]]; then
    "$BIN" --log-level error synth tile --trees "$trees" --size "$side" --seed 7 "$@" --out "$OUT/$name" >/dev/null
  fi
}

# timed_tile INPUT OUT_DIR [FLAGS...]: prints "wall_s peak_MB cpu_s found modelled measured_only failed".
timed_tile() {
  local input=$1 out=$2
  shift 2
  /usr/bin/time -v "$BIN" --threads "$THREADS" --log-level error --json tile "$input" --out "$out" --overwrite "$@" \
    >"$out.json" 2>"$out.time" || [[ $? == 3 ]] || { echo "tile failed on $input (see $out.time)" >&2; return 1; }
  python3 - "$out.time" "$out.json" <<'PY'
import json, re, sys
text = open(sys.argv[1]).read()
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", text).group(1)
seconds = sum(float(part) * 60 ** i for i, part in enumerate(reversed(wall.split(":"))))
peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024
cpu = sum(float(re.search(rf"{kind} time \(seconds\): (\S+)", text).group(1)) for kind in ("User", "System"))
counts = json.load(open(sys.argv[2]))["counts"]
modelled = counts.get("trees_modelled", counts["trees"])  # older treelobes: no measured-only trees
print(f"{seconds:.1f} {peak:.0f} {cpu:.1f} {counts['trees_found']} {modelled} {counts.get('trees_measured_only', 0)} "
      f"{counts['trees_failed']}")
PY
}

# accuracy TRUTH_CSV OUT_DIR: the found trees against the true trees taller than 5 m
# (bench/tile_accuracy.py: matched by points and by the nearest stem within 2 m).
accuracy() {
  "$BIN" --log-level error convert "$2/points.las" --out "$2/points.csv" >/dev/null
  python3 bench/tile_accuracy.py "$1" "$2"
}

echo "== airborne tiles: scaling (${MODE_FLAGS:-fresh segmentation})"
printf "%-10s %-8s %-7s %-8s %-7s %-7s %-8s %-9s %-7s\n" points side_m wall_s cpu_s peak_MB found modelled measured failed
for target in $ALS_SIZES; do
  synth_tile "als_$target" "$target" "${ALS_FLAGS[@]}"
  tile="$OUT/als_$target/tile.las"
  read -r wall peak cpu found modelled measured failed < <(timed_tile "$tile" "$OUT/als_${target}_out" $MODE_FLAGS)
  printf "%-10s %-8s %-7s %-8s %-7s %-7s %-8s %-9s %-7s\n" "$(summary_value "$OUT/als_$target" points)" "$(summary_value "$OUT/als_$target" tile size_m)" "$wall" "$cpu" "$peak" "$found" "$modelled" "$measured" "$failed"
  echo "   accuracy: $(accuracy "$OUT/als_$target/truth.csv" "$OUT/als_${target}_out")"
done

echo
echo "== terrestrial plot (${MODE_FLAGS:-fresh segmentation})"
synth_tile "tls_$TLS_POINTS" "$TLS_POINTS" "${TLS_FLAGS[@]}"
tile="$OUT/tls_$TLS_POINTS/tile.las"
read -r wall peak cpu found modelled measured failed < <(timed_tile "$tile" "$OUT/tls_out" $MODE_FLAGS)
echo "$(summary_value "$OUT/tls_$TLS_POINTS" points) points: ${wall} s wall, ${cpu} s CPU, ${peak} MB peak; ${found} trees found, ${modelled} modelled, ${measured} measured only, ${failed} failed"
echo "   accuracy: $(accuracy "$OUT/tls_$TLS_POINTS/truth.csv" "$OUT/tls_out")"

if [[ -f "$DATA/treels/pine_plot.las" ]]; then
  echo
  echo "== real TLS plot: treels/pine_plot.las"
  read -r wall peak cpu found modelled measured failed < <(timed_tile "$DATA/treels/pine_plot.las" "$OUT/pine_plot_out" --mode tls)
  echo "${wall} s wall, ${cpu} s CPU, ${peak} MB peak; ${found} trees found, ${modelled} modelled, ${measured} measured only, ${failed} failed"
  python3 - "$OUT/pine_plot_out/trees.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(f"{'tree':>5} {'x':>11} {'y':>12} {'height_m':>8} {'dbh_cm':>7} quality")
for r in rows:
    dbh = f"{100 * float(r['dbh_m']):.1f}" if r["dbh_m"] else "-"
    print(f"{r['tree_id']:>5} {r['x']:>11} {r['y']:>12} {r['height_m']:>8} {dbh:>7} {r['dbh_quality']}")
PY
fi

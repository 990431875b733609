#!/usr/bin/env bash
# Segmentation on synthetic stands that were never used to tune it (docs/segment.md, "Where the
# targets stand"): the stands of bench/segment_bench.sh made again with other seeds, airborne
# (crowded seeds 5-12, open seeds 15-22) and terrestrial (crowded seeds 7-16, open seeds 28-37),
# each with and without crown competition. For every tile one row from bench/segment_eval (trees
# taller than 5 m, a true and a found tree matched when each holds at least half of the other's
# points), then per group the mean F1 and share of points assigned to the right tree, the
# figures the targets are stated in.
# Usage: bench/segment_heldout_bench.sh [WORK_DIR]   (default /tmp/treelobes_segment_heldout;
# generated tiles are kept there and reused). Environment: TREELOBES_BIN (default
# build/bin/treelobes), SEGMENT_EVAL (default build/bin/segment_eval).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
EVAL=${SEGMENT_EVAL:-build/bin/segment_eval}
WORK=${1:-/tmp/treelobes_segment_heldout}
for tool in "$BIN" "$EVAL"; do
  [[ -x "$tool" ]] || { echo "segment_heldout_bench: $tool not found (cmake --build build --target treelobes segment_eval)" >&2; exit 1; }
done
mkdir -p "$WORK"

COMMON=(--slope 20 --roughness 1 --spacing 1.0)
ALS_OPEN=(--trees 25 --size 100 --scanner als)
ALS_CROWDED=(--trees 30 --size 80 --scanner als)
TLS_OPEN=(--trees 10 --size 40 --scanner tls --station-spacing 20 --angular-step 0.25)
TLS_CROWDED=(--trees 12 --size 30 --scanner tls --station-spacing 15 --angular-step 0.25)
tiles=()
# tile NAME SEED ARGS...: generates $WORK/NAME/tile.las once, and its competing twin.
tile() {
  local name=$1 seed=$2
  shift 2
  for variant in "" _competing; do
    if [[ ! -f "$WORK/$name$variant/tile.las" ]]; then
      echo "generating $name$variant" >&2
      "$BIN" --log-level error synth tile --out "$WORK/$name$variant" --seed "$seed" "${COMMON[@]}" "$@" \
        ${variant:+--competition} >/dev/null
    fi
    tiles+=("$name$variant")
  done
}
for s in 15 16 17 18 19 20 21 22; do tile "als_open_$s" "$s" "${ALS_OPEN[@]}"; done
for s in 5 6 7 8 9 10 11 12; do tile "als_crowded_$s" "$s" "${ALS_CROWDED[@]}"; done
for s in 28 29 30 31 32 33 34 35 36 37; do tile "tls_open_$s" "$s" "${TLS_OPEN[@]}"; done
for s in 7 8 9 10 11 12 13 14 15 16; do tile "tls_crowded_$s" "$s" "${TLS_CROWDED[@]}"; done

results="$WORK/results.txt"
done_count=0
for name in "${tiles[@]}"; do
  mode=${name%%_*}
  echo "$name $("$EVAL" "$WORK/$name/tile.las" --reference treeID --mode "$mode")"
  done_count=$((done_count + 1))
  echo "scored $done_count/${#tiles[@]}: $name" >&2
done >"$results"
python3 - "$results" <<'PY'
import collections, json, sys
groups = collections.defaultdict(list)
print(f"{'tile':<26} {'true':>5} {'found':>5} {'matched':>7} {'F1':>6} {'right %':>7}")
for line in open(sys.argv[1]):
    name, result = line.split(" ", 1)
    s = json.loads(result)["score"]
    print(f"{name:<26} {s['reference_trees']:5d} {s['found_trees']:5d} {s['matched']:7d} {s['f1']:6.3f} {100 * s['points_right']:7.1f}")
    scanner, stand = name.split("_")[:2]
    groups[(scanner.upper(), stand, "competing" if name.endswith("_competing") else "grown through")].append(s)
print()
print(f"{'group (means over tiles)':<34} {'tiles':>5} {'F1':>6} {'right %':>7}")
for (scanner, stand, crowns), scores in sorted(groups.items()):
    f1 = sum(s["f1"] for s in scores) / len(scores)
    right = sum(s["points_right"] for s in scores) / len(scores)
    print(f"{scanner + ' ' + stand + ', ' + crowns:<34} {len(scores):5d} {f1:6.3f} {100 * right:7.1f}")
PY

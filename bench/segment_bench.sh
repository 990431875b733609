#!/usr/bin/env bash
# Terrain + tree segmentation figures (docs/segment.md), from bench/segment_eval (the library
# through a small program: terrain, segmentation, scoring against per-point reference labels):
#   1. synthetic tiles with truth (`treelobes synth tile`: mixed species of the library, 20-degree
#      slope, 1 m roughness, understory): detection F1 of trees taller than 5 m and the share of
#      points assigned to the right tree, ALS and TLS, open stands (25 trees on 1 ha, 10 on
#      40 x 40 m) and crowded ones (30 on 80 x 80 m, 12 on 30 x 30 m: the synth tile relaxes its
#      spacing and broad crowns interpenetrate), with the input's ground class and with the ground
#      filtered afresh (--ignore-classification); and the same stands with crown competition
#      (`synth tile --competition`: crowns cut where a neighbour owns the canopy); and two dense
#      conifer stands (80 pines on 50 x 50 m, crowns touching) with both stand presets;
#   2. sparse airborne surveys (the ALS stands at 0.025-4 pulses per m^2) with the CHM grid from the
#      returns' spacing and fixed, and lidR/Megaplot.las (1.5 returns per m^2) trees found;
#   3. lidR/MixedConifer.las against lidR's treeID (the broadleaf and conifer stand presets);
#   4. treels/pine_plot.las: stems found, with their positions and diameters (--stand conifer,
#      and the heights the broadleaf default gives);
#   5. timings and peak memory for about 0.25M, 1M and 4M ALS points (a synthetic tile and its
#      2 x 2 and 4 x 4 copies side by side) and the TLS tiles.
# Matching rule: a true tree and a found tree match when each holds at least half of the other's
# points (segment/segmentation_score.hpp).
# Usage: bench/segment_bench.sh [WORK_DIR]   (default /tmp/treelobes_segment_bench; generated
# tiles are kept there and reused). Environment: TREELOBES_BIN (default build/bin/treelobes),
# SEGMENT_EVAL (default build/bin/segment_eval), TREELOBES_REAL_DATA (default ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
EVAL=${SEGMENT_EVAL:-build/bin/segment_eval}
DATA=${TREELOBES_REAL_DATA:-../shared/data}
WORK=${1:-/tmp/treelobes_segment_bench}
for tool in "$BIN" "$EVAL"; do
  [[ -x "$tool" ]] || { echo "segment_bench: $tool not found (cmake --build build --target treelobes segment_eval)" >&2; exit 1; }
done
[[ -d "$DATA" ]] || { echo "segment_bench: real data folder $DATA not found (set TREELOBES_REAL_DATA)" >&2; exit 1; }
mkdir -p "$WORK"

COMMON=(--slope 20 --roughness 1 --spacing 1.0)
# tile NAME SEED ARGS...: generates $WORK/NAME/tile.las once.
tile() {
  local name=$1 seed=$2
  shift 2
  [[ -f "$WORK/$name/tile.las" ]] && return 0
  echo "generating $name (synth tile --seed $seed $*)" >&2
  "$BIN" --log-level error synth tile --out "$WORK/$name" --seed "$seed" "${COMMON[@]}" "$@" >/dev/null
}
for s in 11 12 13 14; do tile "als_open_$s" "$s" --trees 25 --size 100 --scanner als; done
for s in 1 2 3 4; do tile "als_crowded_$s" "$s" --trees 30 --size 80 --scanner als; done
for s in 21 22 23 24 25 26 27; do tile "tls_open_$s" "$s" --trees 10 --size 40 --scanner tls --station-spacing 20 --angular-step 0.25; done
for s in 1 2 3 4 5 6; do tile "tls_crowded_$s" "$s" --trees 12 --size 30 --scanner tls --station-spacing 15 --angular-step 0.25; done
# The same stands with crown competition (`synth tile --competition`): branches that grow where
# a neighbour owns the canopy are cut, as in a closed stand, instead of interpenetrating.
for s in 11 12 13 14; do tile "als_open_${s}_competing" "$s" --trees 25 --size 100 --scanner als --competition; done
for s in 1 2 3 4; do tile "als_crowded_${s}_competing" "$s" --trees 30 --size 80 --scanner als --competition; done
for s in 21 22 23 24 25 26 27; do tile "tls_open_${s}_competing" "$s" --trees 10 --size 40 --scanner tls --station-spacing 20 --angular-step 0.25 --competition; done
for s in 1 2 3 4 5 6; do tile "tls_crowded_${s}_competing" "$s" --trees 12 --size 30 --scanner tls --station-spacing 15 --angular-step 0.25 --competition; done
# Dense conifer stands for the stand presets (`--stand`): 80 pines on 50 x 50 m whose narrow
# crowns touch (spacing 0.5 x the summed crown radii), as in lidR's MixedConifer.
for s in 1 2; do
  [[ -f "$WORK/als_pine_dense_$s/tile.las" ]] && continue
  echo "generating als_pine_dense_$s" >&2
  "$BIN" --log-level error synth tile --out "$WORK/als_pine_dense_$s" --seed "$s" --slope 20 --roughness 1 --spacing 0.5 \
    --trees 80 --size 50 --scanner als --species pine >/dev/null
done

# row LABEL ARGS...: one table row from one segment_eval run.
row() {
  local label=$1 result
  shift
  result=$("$EVAL" "$@")
  python3 - "$label" "$result" <<'PY'
import json, sys
d = json.loads(sys.argv[2])
s = d.get("score")
if s:
    score = f"{s['reference_trees']:5d} {s['found_trees']:5d} {s['matched']:5d} {s['f1']:6.3f} {100 * s['points_right']:6.1f}"
else:
    score = "    -     -     -      -      -"
g = d.get("ground_check")
ground = f"{100 * g['found_as_ground']:6.1f} {g['rms_height_m']:6.3f}" if g else "     -      -"
print(f"{sys.argv[1]:<34} {d['ground_source']:<10} {d['mode']:<4} {score} {ground} {d['seconds']['total']:7.2f} {d['peak_memory_mb']:7.0f}")
PY
}
# g_found% / g_rms_m: the input's class-2 points found as ground / their RMS height above the DTM.
header() { printf '%-34s %-10s %-4s %5s %5s %5s %6s %6s %6s %6s %7s %7s\n' "$1" ground mode true found match F1 right% g_fnd% g_rms seconds peak_MB; }

echo "== synthetic tiles (trees > 5 m; right% = points of those trees in their matched tree)"
header "tile"
for s in 11 12 13 14; do row "ALS open, seed $s" "$WORK/als_open_$s/tile.las" --reference treeID; done
for s in 11 12 13 14; do row "ALS open, seed $s, ground filtered" "$WORK/als_open_$s/tile.las" --reference treeID --ignore-classification; done
for s in 1 2 3 4; do row "ALS crowded, seed $s" "$WORK/als_crowded_$s/tile.las" --reference treeID; done
for s in 21 22 23 24 25 26 27; do row "TLS open, seed $s" "$WORK/tls_open_$s/tile.las" --reference treeID; done
for s in 21 22 23; do row "TLS open, seed $s, ground filtered" "$WORK/tls_open_$s/tile.las" --reference treeID --ignore-classification; done
for s in 1 2 3 4 5 6; do row "TLS crowded, seed $s" "$WORK/tls_crowded_$s/tile.las" --reference treeID; done
for s in 11 12 13 14; do row "ALS open, seed $s, competing" "$WORK/als_open_${s}_competing/tile.las" --reference treeID; done
for s in 1 2 3 4; do row "ALS crowded, seed $s, competing" "$WORK/als_crowded_${s}_competing/tile.las" --reference treeID; done
for s in 21 22 23 24 25 26 27; do row "TLS open, seed $s, competing" "$WORK/tls_open_${s}_competing/tile.las" --reference treeID; done
for s in 1 2 3 4 5 6; do row "TLS crowded, seed $s, competing" "$WORK/tls_crowded_${s}_competing/tile.las" --reference treeID; done
for s in 1 2; do
  row "ALS dense pines, seed $s" "$WORK/als_pine_dense_$s/tile.las" --reference treeID
  row "ALS dense pines, seed $s, conifer" "$WORK/als_pine_dense_$s/tile.las" --reference treeID --stand conifer
done
# Crown cover (summed true crown areas over the plot area): how far the crowns interpenetrate.
echo "crown cover (sum of the true crown areas / plot area):"
for d in "$WORK"/als_*/ "$WORK"/tls_*/; do
  python3 - "$d" <<'PY'
import csv, json, math, sys
folder = sys.argv[1].rstrip("/")
side = json.load(open(folder + "/summary.json"))["options"]["size"]
area = sum(math.pi / 4 * float(r["crown_diameter_m"]) ** 2 for r in csv.DictReader(open(folder + "/truth.csv")))
print(f"  {folder.split('/')[-1]}: {area / side ** 2:.2f}")
PY
done
echo
echo "== sparse airborne surveys: the open and crowded stands above at 0.025-4 pulses per m^2, the CHM's"
echo "   cell and discs from the returns' spacing (default) and fixed at 0.5 m cells and 0.15 m discs;"
echo "   pulses = the survey's pulse density as tile reads it (first returns over the footprint)"
for pd in 0.025 0.05 0.1 0.25 0.5 1 2 4; do
  for s in 11 12 13 14; do tile "als_open_${s}_pd$pd" "$s" --trees 25 --size 100 --scanner als --pulse-density "$pd"; done
  for s in 1 2 3 4; do tile "als_crowded_${s}_pd$pd" "$s" --trees 30 --size 80 --scanner als --pulse-density "$pd"; done
done
# group_row LABEL ARGS -- TILES...: mean F1, points right and found / true trees over the tiles.
group_row() {
  local label=$1 args=() results=()
  shift
  while [[ $1 != -- ]]; do args+=("$1"); shift; done
  shift
  for t in "$@"; do results+=("$("$EVAL" "$t/tile.las" --reference treeID "${args[@]}")"); done
  python3 - "$label" "${results[@]}" <<'PY'
import json, sys
runs = [json.loads(r) for r in sys.argv[2:]]
f1 = [r["score"]["f1"] for r in runs]
right = [r["score"]["points_right"] for r in runs]
found = sum(r["score"]["found_trees"] for r in runs)
true = sum(r["score"]["reference_trees"] for r in runs)
chm = runs[0]["chm"]
pulses = [r["chm"]["pulse_density"] for r in runs]
print(f"{sys.argv[1]:<40} {' '.join(f'{v:.3f}' for v in f1)}  mean F1 {sum(f1) / len(f1):.3f}  right {100 * sum(right) / len(right):5.1f} %"
      f"  found {found} of {true}  pulses {min(pulses):.3f}-{max(pulses):.3f}/m^2"
      f"  (first tile: spacing {chm['return_spacing']:.2f} m, cell {chm['cell']:.2f} m, disc {chm['point_radius']:.2f} m)")
PY
}
for pd in 0.025 0.05 0.1 0.25 0.5 1 2 4; do
  for stand in open crowded; do
    tiles=("$WORK"/als_${stand}_*_pd$pd)
    group_row "$pd pulses/m^2, $stand" -- "${tiles[@]}"
    group_row "$pd pulses/m^2, $stand, fixed grid" --set cell_per_spacing=0 --set disc_per_spacing=0 -- "${tiles[@]}"
  done
done
echo "lidR Megaplot.las (no reference), trees found:"
for stand in broadleaf conifer; do
  python3 - "$stand" "$("$EVAL" "$DATA/lidr/Megaplot.las" --stand "$stand")" \
    "$("$EVAL" "$DATA/lidr/Megaplot.las" --stand "$stand" --set cell_per_spacing=0 --set disc_per_spacing=0)" <<'PY'
import json, sys
grown, fixed = json.loads(sys.argv[2]), json.loads(sys.argv[3])
c = grown["chm"]
print(f"  --stand {sys.argv[1]}: {grown['trees']} (spacing {c['return_spacing']:.2f} m, cell {c['cell']:.2f} m, disc {c['point_radius']:.2f} m);"
      f" fixed grid: {fixed['trees']}")
PY
done

echo
echo "== lidR MixedConifer.las against lidR's treeID (trees > 5 m)"
header "setting"
row "--stand broadleaf (default)" "$DATA/lidr/MixedConifer.las" --reference treeID
row "--stand conifer" "$DATA/lidr/MixedConifer.las" --reference treeID --stand conifer
echo "matching table (--stand conifer):"
python3 - "$("$EVAL" "$DATA/lidr/MixedConifer.las" --reference treeID --stand conifer)" <<'PY'
import json, sys
d = json.loads(sys.argv[1])
print("| height (lidR tree) | lidR trees | found | matched |")
print("|---|---|---|---|")
for r in d["score"]["by_height"]:
    print(f"| {r['height']} | {r['reference']} | {r['found']} | {r['matched']} |")
PY

echo
echo "== TreeLS pine_plot.las: stems (--stand conifer; heights with the broadleaf default in the last column)"
python3 - "$("$EVAL" "$DATA/treels/pine_plot.las" --trees --stand conifer)" "$("$EVAL" "$DATA/treels/pine_plot.las" --trees)" <<'PY'
import json, sys
d, broadleaf = json.loads(sys.argv[1]), json.loads(sys.argv[2])
print(f"{d['trees']} trees ({d['mode_reason']}; ground {d['ground_source']}), {d['seconds']['total']:.2f} s")
print("| id | x | y | height m | stem diameter at 1-2 m, cm | points | height m, broadleaf |")
print("|---|---|---|---|---|---|---|")
for t, b in zip(d["tree_list"], broadleaf["tree_list"]):
    print(f"| {t['id']} | {t['x']:.2f} | {t['y']:.2f} | {t['height']:.1f} | {200 * t['stem_radius']:.1f} | {t['points']} | {b['height']:.1f} |")
PY

echo
echo "== scaling (ALS open seed 11 and its 2 x 2, 3 x 3 and 6 x 6 copies; TLS tiles as generated)"
printf '%-34s %9s %9s %9s %9s %8s\n' input points terrain_s segment_s total_s peak_MB
scale() {
  local label=$1 result
  shift
  result=$("$EVAL" "$@")
  python3 - "$label" "$result" <<'PY'
import json, sys
d = json.loads(sys.argv[2])
t = d["seconds"]
print(f"{sys.argv[1]:<34} {d['points']:9d} {t['terrain']:9.2f} {t['segment']:9.2f} {t['total']:9.2f} {d['peak_memory_mb']:8.0f}")
PY
}
scale "ALS x1" "$WORK/als_open_11/tile.las"
scale "ALS x4 (2 x 2 copies)" "$WORK/als_open_11/tile.las" --replicate 2
scale "ALS x9 (3 x 3 copies)" "$WORK/als_open_11/tile.las" --replicate 3
scale "ALS x36 (6 x 6 copies)" "$WORK/als_open_11/tile.las" --replicate 6
for s in 21 22 23; do scale "TLS open seed $s" "$WORK/tls_open_$s/tile.las"; done
for s in 1 2 3; do scale "TLS crowded seed $s" "$WORK/tls_crowded_$s/tile.las"; done

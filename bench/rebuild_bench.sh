#!/usr/bin/env bash
# `treelobes rebuild` on heavy polygonal trees, the experiment of Livny et al. 2011, §7 (Xfrog
# models sampled into points and rebuilt as lobe-based trees: 56 MB -> 60 kB for a tree,
# 47 MB -> 45 kB for a shrub). The heavy trees are `treelobes synth tree` meshes written as OBJ
# with bark/leaf materials (dense leaf geometry, up to 250 000 leaves), one per species.
# Prints per species: input MB and triangles, .tlobe and .dbf6 kB, compression factor (input /
# .tlobe), symmetric mean / p95 / Hausdorff distances original <-> rebuilt in % of the bounding-box
# diagonal, silhouette IoU as drawn and of the crown outlines (front, side, top), leaf area ratio
# rebuilt / original, rebuild wall and CPU time and peak memory; then the paper's figures; then the
# IoU ceiling: each original against the same tree with its leaves drawn again (`treelobes compare`).
# Usage: bench/rebuild_bench.sh [BUILD_DIR] [OUT_DIR] [SPECIES...]   (default: all 12 species)
# Extra rebuild flags: REBUILD_FLAGS="--scan tls --samples 300000" bench/rebuild_bench.sh
# Another tree of each species: TREE_SEED=2 bench/rebuild_bench.sh (default 1; outputs in OUT_DIR/SPECIES_SEED
# for seeds other than 1)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-/tmp/treelobes_rebuild_bench}
bin=$build/bin/treelobes
mkdir -p "$out"
seed=${TREE_SEED:-1}
species=(mahogany bischofia_polycarpa delonix lagerstroemia ailanthus_altissima palm terminalia pine willow ficus_virens birch oak)
if [ $# -gt 2 ]; then species=("${@:3}"); fi
printf '%-20s %8s %9s %8s %7s %7s %7s %7s %7s %5s %5s %5s %5s %5s %5s %6s %7s %7s %7s\n' \
  species in_MB triangles tlobe_kB dbf6_kB factor mean_% p95_% haus_% iouF iouS iouT crF crS crT leafA time_s cpu_s peak_MB
for s in "${species[@]}"; do
  if [ ! -s "$out/${s}_${seed}_mesh.obj" ]; then
    "$bin" synth tree --species "$s" --out "$out" --seed "$seed" --mesh-format obj --angular-step 1 --log-level error > /dev/null
  fi
  rebuilt=$out/$s
  if [ "$seed" != 1 ]; then rebuilt=$out/${s}_$seed; fi
  # shellcheck disable=SC2086
  "$bin" rebuild "$out/${s}_${seed}_mesh.obj" --out "$rebuilt" --species "$s" --log-level error ${REBUILD_FLAGS:-} > /dev/null
  python3 - "$rebuilt/report.json" "$s" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
z, f = r["sizes"], r["fidelity"]
sym, iou, crown = f["symmetric"], f["silhouette_iou"], f["crown_silhouette_iou"]
ratio = f["leaf_area"]["ratio"]
print("%-20s %8.1f %9d %8.1f %7.1f %7.0f %7.2f %7.2f %7.2f %5.2f %5.2f %5.2f %5.2f %5.2f %5.2f %6s %7.1f %7.1f %7.0f" % (
    sys.argv[2], z["original_bytes"] / 1e6, r["input_mesh"]["triangles"], z["tlobe_bytes"] / 1e3, z["dbf6_bytes"] / 1e3,
    z["compression_factor"], 100 * sym["mean_of_diagonal"], 100 * sym["p95_of_diagonal"], 100 * sym["max_of_diagonal"],
    iou["front"], iou["side"], iou["top"], crown["front"], crown["side"], crown["top"], "-" if ratio is None else "%.2f" % ratio, r["seconds"]["total"], r["seconds"]["cpu"], r["peak_memory_mb"]))
PY
done
printf '%-20s %8.1f %9s %8.1f %7s %7.0f\n' "paper: Xfrog tree" 56 - 60 - 933
printf '%-20s %8.1f %9s %8.1f %7s %7.0f\n' "paper: Xfrog shrub" 47 - 45 - 1044
# The ceiling of the silhouette IoU: each original against the same tree with its leaves drawn
# again (same branches, same leaf area, 0.7 x the leaves, each 1/sqrt(0.7) larger; 175 000 is
# 0.7 x the default cap of 250 000 leaves, which the heavier species reach).
printf '\n%-20s %5s %5s %5s %5s %5s %5s  (original against itself re-leafed)\n' species iouF iouS iouT crF crS crT
for s in "${species[@]}"; do
  if [ ! -s "$out/releafed/${s}_${seed}_mesh.obj" ]; then
    "$bin" synth tree --species "$s" --out "$out/releafed" --seed "$seed" --mesh-format obj --angular-step 1 --leaf-density 0.7 \
      --max-leaves 175000 --log-level error > /dev/null
  fi
  "$bin" --json compare "$out/${s}_${seed}_mesh.obj" "$out/releafed/${s}_${seed}_mesh.obj" --log-level error | python3 -c '
import json, sys
f = json.load(sys.stdin)["fidelity"]
iou, crown = f["silhouette_iou"], f["crown_silhouette_iou"]
print("%-20s %5.2f %5.2f %5.2f %5.2f %5.2f %5.2f" % (sys.argv[1], iou["front"], iou["side"], iou["top"], crown["front"], crown["side"], crown["top"]))
' "$s"
done

#!/usr/bin/env bash
# Lobes: Table-2-style figures for every single-tree scan of ../shared/data -
# lobe count, .tlobe size (target < 40 kB), reconstruction and lobe times - then synthesis of
# each .tlobe: texturing time, triangles, LOD extraction time, input point -> mesh distances.
# Usage: bench/lobes_bench.sh [BUILD_DIR] [OUT_DIR]   (defaults: build, /tmp/treelobes_lobes_bench)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-/tmp/treelobes_lobes_bench}
data=${TREELOBES_REAL_DATA:-$here/../shared/data}
bin=$build/bin/treelobes
mkdir -p "$out"
trees=(adtree/tree1.xyz adtree/tree7.xyz adtree/tree13.xyz adtree/Lille_11.xyz adtree/ahn3_delft.xyz
       archi/tree1_points.las woodske/HS_wood.csv woodske/OR_wood.csv woodske/SW_wood.csv treels/pine.las)
printf '%-22s %6s %9s %6s %8s %8s %8s %9s %10s %8s %8s %8s\n' tree lobes tlobe_kB cell_m recon_s lobes_s encode_s texture_s triangles lod50_s med_m p95_m
for t in "${trees[@]}"; do
  stem=$(basename "${t%.*}")
  "$bin" lobes "$data/$t" --out "$out" --log-level error > /dev/null
  s=$out/${stem}_lobes.json
  "$bin" synthesize "$out/$stem.tlobe" --out "$out/${stem}_tree.ply" --points "$data/$t" --log-level error > /dev/null
  "$bin" synthesize "$out/$stem.tlobe" --out "$out/${stem}_lod50.ply" --lod 0.5 --log-level error > /dev/null
  python3 - "$s" "$out/${stem}_tree.json" "$out/${stem}_lod50.json" "$stem" <<'PY'
import json, sys
s, f, l = (json.load(open(p)) for p in sys.argv[1:4])
sec = s["seconds"]
print("%-22s %6d %9.1f %6s %8.2f %8.2f %8.2f %9.2f %10d %8.3f %8.3f %8.3f" % (sys.argv[4], s["lobe_count"], s["tlobe_bytes"] / 1000,
      s.get("occupancy_cell"), sec["reconstruct"], sec["lobes"], sec["encode and verify"], f["seconds"]["texturing"], f["triangles"], l["seconds"]["lod_extraction"],
      f["fidelity"]["median_point_to_mesh"], f["fidelity"]["p95_point_to_mesh"]))
PY
done

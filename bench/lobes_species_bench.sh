#!/usr/bin/env bash
# Lobes on synthetic trees of every species of config/species.yaml: a simulated TLS
# scan per species (`treelobes synth tree`, 0.3 deg steps), then `lobes --species` and
# `synthesize --points` on it. Prints lobe count, .tlobe size and occupancy cell, times (reconstruction,
# lobes, .tlobe encode, texturing), triangles and fidelity.
# Usage: bench/lobes_species_bench.sh [BUILD_DIR] [OUT_DIR] [SPECIES...]   (default: all 12 species)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
out=${2:-/tmp/treelobes_lobes_species}
bin=$build/bin/treelobes
mkdir -p "$out"
species=(mahogany bischofia_polycarpa delonix lagerstroemia ailanthus_altissima palm terminalia pine willow ficus_virens birch oak)
if [ $# -gt 2 ]; then species=("${@:3}"); fi
printf '%-20s %8s %6s %9s %6s %8s %8s %8s %9s %10s %8s %8s\n' species points lobes tlobe_kB cell_m recon_s lobes_s encode_s texture_s triangles med_m p95_m
for s in "${species[@]}"; do
  "$bin" synth tree --species "$s" --out "$out" --seed 1 --no-mesh --angular-step 0.3 --log-level error > /dev/null
  "$bin" lobes "$out/${s}_1.las" --species "$s" --out "$out" --log-level error > /dev/null
  "$bin" synthesize "$out/${s}_1.tlobe" --out "$out/${s}_1_tree.ply" --points "$out/${s}_1.las" \
    --preview "$out/${s}_1_preview.png" --log-level error > /dev/null
  python3 - "$out/${s}_1_lobes.json" "$out/${s}_1_tree.json" "$s" <<'PY'
import json, sys
s, f = (json.load(open(p)) for p in sys.argv[1:3])
sec = s["seconds"]
print("%-20s %8d %6d %9.1f %6s %8.2f %8.2f %8.2f %9.2f %10d %8.3f %8.3f" % (sys.argv[3], f["fidelity"]["points"], s["lobe_count"],
      s["tlobe_bytes"] / 1000, s.get("occupancy_cell"), sec["reconstruct"], sec["lobes"], sec["encode and verify"],
      f["seconds"]["texturing"], f["triangles"],
      f["fidelity"]["median_point_to_mesh"], f["fidelity"]["p95_point_to_mesh"]))
PY
done

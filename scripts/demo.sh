#!/usr/bin/env bash
# Set-up (scripts/setup.sh), then the main job on the bundled synthetic sample (data/synthetic/):
# describe the files, reconstruct two scanned trees (skeleton, allometric radii, branch mesh),
# score the skeletons against their ground truth, build the lobe-based representation and a full
# synthesized tree, compress the skeletons as DBF6, and draw previews. Outputs go to ./demo-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
BIN=build/bin/treelobes
OUT=demo-out
SAMPLE=data/synthetic
rm -rf "$OUT"
mkdir -p "$OUT"

step() { echo; echo "== $*"; }

step "info: the sample's scans"
"$BIN" info "$SAMPLE"/*.las "$SAMPLE/tile/tile.las"

step "reconstruct: skeleton, radii and branch mesh of two scanned trees"
"$BIN" reconstruct "$SAMPLE/lagerstroemia_2.las" --species lagerstroemia --out "$OUT/reconstruct"
"$BIN" reconstruct "$SAMPLE/palm_1.las" --species palm --out "$OUT/reconstruct"

step "eval: reconstructed skeletons against the true ones"
for tree in lagerstroemia_2 palm_1; do
    args=(eval skeleton --skeleton "$OUT/reconstruct/${tree}_skeleton.ply" --reference "$SAMPLE/${tree}_skeleton.ply")
    "$BIN" "${args[@]}"
    "$BIN" --json "${args[@]}" > "$OUT/eval_${tree}.json"
done

step "lobes + synthesize: lobe-based representation and full tree of the Lagerstroemia"
"$BIN" lobes "$SAMPLE/lagerstroemia_2.las" --species lagerstroemia --out "$OUT/lobes"
"$BIN" synthesize "$OUT/lobes/lagerstroemia_2.tlobe" --out "$OUT/lobes/lagerstroemia_2_synthesized.ply"

step "encode: DBF6 chain code with 3 levels of detail, decoded back"
"$BIN" encode "$OUT/reconstruct/lagerstroemia_2_skeleton.ply" --resolution 5 --lods 3 --out "$OUT/lagerstroemia_2.dbf6" --stats
"$BIN" decode "$OUT/lagerstroemia_2.dbf6" --lod 0 --out "$OUT/lagerstroemia_2_lod0.ply"

step "render: scan, reconstruction and truth side by side"
"$BIN" render "$SAMPLE/lagerstroemia_2.las" "$OUT/reconstruct/lagerstroemia_2_skeleton.ply" \
    "$SAMPLE/lagerstroemia_2_skeleton.ply" --out "$OUT/lagerstroemia_2.png"

echo
echo "demo: outputs in $OUT/"

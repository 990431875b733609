#!/usr/bin/env bash
# Set-up (scripts/setup.sh), then the main job on the bundled synthetic sample (data/synthetic/):
# `treelobes tile` on a forest tile (ground, trees, a model and measures per tree, a table and a
# top-view picture), then the single-tree stages: reconstruct two scanned trees (skeleton,
# allometric radii, branch mesh), score a skeleton against the part of its true skeleton the
# scan sees, build the lobe-based representation and a full synthesized tree, compress a
# skeleton as DBF6, and draw a preview. Outputs go to ./demo-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
BIN=build/bin/treelobes
OUT=demo-out
SAMPLE=data/synthetic
rm -rf "$OUT"
mkdir -p "$OUT"

step() { echo; echo "== $*"; }
truth_dbh() { awk -F': *' '/"dbh_m"/ { printf "%.3f", $2 }' "$SAMPLE/$1_truth.json"; }

step "info: the sample's scans"
"$BIN" info "$SAMPLE"/*.las "$SAMPLE/tile/tile.las"

step "tile: a forest tile in, every tree out"
# Exit 3 means the tile is done but some trees failed (listed in failures.jsonl).
status=0
"$BIN" tile "$SAMPLE/tile/tile.las" --out "$OUT/tile" || status=$?
((status == 0 || status == 3)) || exit "$status"
echo
echo "trees found (from $OUT/tile/trees.csv; heights in metres above the ground; an airborne scan"
echo "does not see stems, so DBH is 'not_visible' rather than guessed, and the woody volume is an"
echo "estimate: the crown's skeleton on a stem of height / 50 at its foot; a tree with too few points"
echo "for a model is measured only, without a woody volume):"
# Columns by their names in the header (docs/tile.md lists them).
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i
                   printf "%5s %10s %10s %7s %-12s %8s %9s %10s %7s\n", "tree", "x", "y", "height", "DBH", "crown_d", "crown_m3", "wood_m3", "points"; next }
         { dbh = $c["dbh_m"] == "" ? $c["dbh_quality"] : $c["dbh_m"] " m"
           printf "%5s %10s %10s %7s %-12s %8s %9s %10s %7s\n", $c["tree_id"], $c["x"], $c["y"], $c["height_m"], dbh, $c["crown_diameter_m"],
                  $c["crown_volume_m3"], ($c["model"] == "ok" ? $c["woody_volume_m3"] : "-"), $c["points"] }' \
    "$OUT/tile/trees.csv"
modelled=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "model") m = i; next } $m == "ok"' "$OUT/tile/trees.csv" | wc -l)
listed=$(($(wc -l <"$OUT/tile/trees.csv") - 1))
echo "$listed trees: $modelled modelled, $((listed - modelled)) measured only (fewer than 50 points); the tile holds $(($(wc -l <"$SAMPLE/tile/truth.csv") - 1)) true trees ($SAMPLE/tile/truth.csv)"
if [[ -f "$OUT/tile/failures.jsonl" ]]; then
    echo "$(wc -l <"$OUT/tile/failures.jsonl") trees failed: $OUT/tile/failures.jsonl"
fi
echo "picture: $OUT/tile/top_view.png (each tree in its colour, stems as dots with their ids)"
echo "also: $OUT/tile/points.las (treeID, HeightAboveGround), trees.geojson, crowns.geojson (crown outlines), tile.forest,"
echo "      trees/ (per tree skeleton, mesh, .tlobe, .dbf6)"

step "reconstruct: skeleton, radii and branch mesh of two scanned trees"
# A leaf-off tree of heaven (a winter scan, as QSM campaigns take them) and a leafy palm.
"$BIN" reconstruct "$SAMPLE/ailanthus_altissima_5.las" --species ailanthus_altissima --out "$OUT/reconstruct"
"$BIN" reconstruct "$SAMPLE/palm_1.las" --species palm --out "$OUT/reconstruct"
echo "true DBH: ailanthus $(truth_dbh ailanthus_altissima_5) m, palm $(truth_dbh palm_1) m ($SAMPLE/*_truth.json)"

step "eval: the reconstructed skeleton against the part of the true one its scan sees"
# The true skeleton holds every twig, also those too thin for the scan to hit; --visible-in scores
# the skeleton's parts against the internodes the scan touched and asks for those it saw with 5
# points or more (each with its way to the root). Trunk radii are compared at 1.3 m.
args=(eval skeleton --skeleton "$OUT/reconstruct/ailanthus_altissima_5_skeleton.ply"
      --reference "$SAMPLE/ailanthus_altissima_5_skeleton.ply" --visible-in "$SAMPLE/ailanthus_altissima_5.las")
"$BIN" "${args[@]}"
"$BIN" --json "${args[@]}" > "$OUT/eval_ailanthus_altissima_5.json"

step "lobes + synthesize: lobe-based representation of a scanned mahogany, and the full tree drawn from it"
"$BIN" lobes "$SAMPLE/mahogany_1.las" --species mahogany --out "$OUT/lobes"
"$BIN" synthesize "$OUT/lobes/mahogany_1.tlobe" --out "$OUT/lobes/mahogany_1_synthesized.ply" \
    --points "$SAMPLE/mahogany_1.las" --preview "$OUT/lobes/mahogany_1_preview.png"
echo "picture: $OUT/lobes/mahogany_1_preview.png (the scan | the tree synthesized from its .tlobe)"

step "encode: DBF6 chain code with 3 levels of detail, decoded back"
"$BIN" encode "$OUT/reconstruct/ailanthus_altissima_5_skeleton.ply" --resolution 5 --lods 3 --out "$OUT/ailanthus_altissima_5.dbf6" --stats
"$BIN" decode "$OUT/ailanthus_altissima_5.dbf6" --lod 0 --out "$OUT/ailanthus_altissima_5_lod0.ply"

step "render: scan, reconstruction and truth side by side"
"$BIN" render "$SAMPLE/ailanthus_altissima_5.las" "$OUT/reconstruct/ailanthus_altissima_5_skeleton.ply" \
    "$SAMPLE/ailanthus_altissima_5_skeleton.ply" --out "$OUT/ailanthus_altissima_5.png"

echo
echo "demo: outputs in $OUT/"

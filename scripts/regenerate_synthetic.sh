#!/usr/bin/env bash
# Regenerates data/synthetic/ (the committed sample used by the README demo and tests) with the
# `treelobes synth` commands below. Same binary + same species.yaml -> byte-identical files.
#
#   scripts/regenerate_synthetic.sh            rewrite data/synthetic/
#   scripts/regenerate_synthetic.sh --check    regenerate into a temporary folder and compare
#
# The binary is $TREELOBES_BIN, or build/bin/treelobes. Layout: single trees at the top level
# (<species>_<seed>.las, _skeleton.ply, _truth.json, some _mesh.ply), the tile in tile/.
# data/synthetic/README.md is written by hand and not regenerated.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
[[ -x "$BIN" ]] || { echo "regenerate_synthetic: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
export TREELOBES_SPECIES=config/species.yaml
# LAS headers carry a creation date; SOURCE_DATE_EPOCH (the reproducible-builds convention) pins it.
export SOURCE_DATE_EPOCH=${SOURCE_DATE_EPOCH:-1735689600}  # 2025-01-01

generate() {
    local out=$1
    mkdir -p "$out"
    rm -rf "$out/tile" "$out"/*.las "$out"/*.ply "$out"/*_truth.json
    # Small single trees: terrestrial scans (the palm with its mesh) and one airborne.
    "$BIN" --log-level warn synth tree --species palm --seed 1 --height 8 --angular-step 0.8 --max-leaves 1500 --out "$out" >/dev/null
    # The Lagerstroemia at a finer raster (0.4 degrees) with little ground around it: at 0.8 degrees
    # the scan hits too few of its thin stems for a skeleton worth scoring.
    "$BIN" --log-level warn synth tree --species lagerstroemia --seed 2 --height 5 --angular-step 0.4 --ground-margin 0.5 --max-leaves 3000 --no-mesh --out "$out" >/dev/null
    # A 9 m mahogany scanned finely enough (0.6 degrees) for the demo's lobe-based representation
    # to show its structure: 11 lobes on 31 main nodes (coarser steps give 3-6 lobes, the
    # multi-stemmed Lagerstroemia one lobe at its root collar).
    "$BIN" --log-level warn synth tree --species mahogany --seed 1 --height 9 --angular-step 0.6 --ground-margin 0.5 --max-leaves 3000 --no-mesh --out "$out" >/dev/null
    "$BIN" --log-level warn synth tree --species birch --seed 3 --height 9 --scanner als --pulse-density 80 --max-leaves 4000 --no-mesh --out "$out" >/dev/null
    # A leaf-off terrestrial scan (as QSM campaigns scan broadleaves in winter) of an 8 m tree of
    # heaven: the demo's skeleton is scored on it, every branch thicker than 2 cm in sight.
    "$BIN" --log-level warn synth tree --species ailanthus_altissima --seed 5 --height 8 --angular-step 0.4 --ground-margin 0.5 --no-leaves --no-mesh --out "$out" >/dev/null
    # The demo's forest tile: an airborne scan (20 pulses/m^2) of 30 trees of five species on 55 x 55 m
    # of sloping ground with understory and noise; stems at least 0.9 x their summed crown radii
    # apart, so neighbouring crowns touch as in a closed stand instead of growing through each
    # other (the synthetic trees do not react to their neighbours; at the default 0.4 half of a
    # crown can lie inside the next one, docs/segment.md).
    "$BIN" --log-level warn synth tile --trees 30 --size 55 --spacing 0.9 --seed 4 --pulse-density 20 --max-leaves 3000 \
        --species pine birch palm lagerstroemia ailanthus_altissima --out "$out/tile" >/dev/null
    # summary.json holds timings and memory, which differ between runs: not part of the sample. The
    # true skeletons of the tile's trees (3 MB) are left out to keep the sample small; the single
    # trees above carry theirs.
    rm -rf "$out/tile/summary.json" "$out/tile/skeletons"
}

if [[ "${1:-}" == "--check" ]]; then
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    generate "$tmp"
    status=0
    fresh=$(cd "$tmp" && find . -type f | sort)
    kept=$(cd data/synthetic && find . -type f ! -name README.md | sort)
    if [[ "$fresh" != "$kept" ]]; then
        diff <(echo "$kept") <(echo "$fresh") | sed 's/^/  file list: /' >&2 || true
        status=1
    fi
    while read -r f; do
        [[ -f "data/synthetic/$f" ]] || continue
        cmp -s "$tmp/$f" "data/synthetic/$f" || { echo "  differs: $f" >&2; status=1; }
    done <<<"$fresh"
    if ((status)); then
        echo "regenerate_synthetic: data/synthetic differs from a fresh run" >&2
        exit 1
    fi
    echo "data/synthetic is byte-identical to a fresh run ($(echo "$fresh" | wc -l) files)"
else
    generate data/synthetic
    du -sh data/synthetic
fi

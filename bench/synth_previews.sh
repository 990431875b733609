#!/usr/bin/env bash
# One preview per species for docs/species/<species>.png: the synthetic tree's mesh (left) and
# its simulated TLS scan coloured wood/leaf/ground (right), seed 1, height drawn from the species.
# Usage: bench/synth_previews.sh [OUT_DIR] (default docs/species). Binary: $TREELOBES_BIN or build/bin/treelobes.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
OUT=${1:-docs/species}
[[ -x "$BIN" ]] || { echo "synth_previews: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$OUT"
species=$(grep -E '^  - name: ' config/species.yaml | sed 's/.*name: //')
for s in $species; do
    "$BIN" --log-level warn synth tree --species "$s" --seed 1 --angular-step 0.12 --max-leaves 60000 --no-mesh \
        --preview --preview-height 400 --out "$tmp" >/dev/null
    cp "$tmp/${s}_1_preview.png" "$OUT/$s.png"
    rm -f "$tmp"/*
    echo "$OUT/$s.png"
done

#!/usr/bin/env bash
# Synthetic-data benchmark: a 12-species dataset with 40 trees per species (TLS scans,
# true skeletons, labels.csv) and a 100 x 100 m ALS forest tile; prints wall time, peak memory,
# points and sizes. Usage: bench/synth_bench.sh [OUT_DIR] (default /tmp/treelobes_synth_bench).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
OUT=${1:-/tmp/treelobes_synth_bench}
PER_SPECIES=${PER_SPECIES:-40}
TILE_TREES=${TILE_TREES:-150}
[[ -x "$BIN" ]] || { echo "synth_bench: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"

field() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); v=d
for k in sys.argv[2].split('.'): v=v[k]
print(v)" "$1" "$2"; }

echo "== dataset: 12 species x $PER_SPECIES trees (TLS) =="
start=$(date +%s.%N)
"$BIN" --log-level warn synth dataset --per-species "$PER_SPECIES" --seed 1 --out "$OUT/dataset"
end=$(date +%s.%N)
echo "wall $(python3 -c "print(f'{$end-$start:.1f}')") s, peak memory $(field "$OUT/dataset/summary.json" peak_memory_mb) MB," \
     "$(field "$OUT/dataset/summary.json" points) points, $(du -sh "$OUT/dataset" | cut -f1) on disk," \
     "$(find "$OUT/dataset" -name '*.las' | wc -l) scans"
# Per species: trees, mean points per scan, mean height (labels.csv).
python3 - "$OUT/dataset/labels.csv" "$(python3 -c "print($end-$start)")" <<'PY'
import csv, sys, collections
rows = list(csv.DictReader(open(sys.argv[1])))
seconds = float(sys.argv[2])
print(f"{len(rows)} trees in {seconds:.0f} s: {seconds / max(1, len(rows)):.2f} s per tree, "
      f"{sum(int(r['points']) for r in rows) / max(1, len(rows)):.0f} points per tree")
by = collections.defaultdict(list)
for r in rows: by[r['species']].append(r)
for name, rs in by.items():
    print(f"  {name:22s} {len(rs):3d} trees, {sum(int(r['points']) for r in rs) / len(rs):9.0f} points/tree, "
          f"height {sum(float(r['height_m']) for r in rs) / len(rs):5.1f} m")
PY

echo "== tile: 100 x 100 m, $TILE_TREES trees (ALS) =="
start=$(date +%s.%N)
"$BIN" --log-level warn synth tile --trees "$TILE_TREES" --size 100 --seed 1 --out "$OUT/tile"
end=$(date +%s.%N)
echo "wall $(python3 -c "print(f'{$end-$start:.1f}')") s (grow $(field "$OUT/tile/summary.json" seconds.grow) s," \
     "scan $(field "$OUT/tile/summary.json" seconds.scan) s), peak memory $(field "$OUT/tile/summary.json" peak_memory_mb) MB," \
     "$(field "$OUT/tile/summary.json" points) points ($(field "$OUT/tile/summary.json" points_per_m2) per m^2)," \
     "$(du -sh "$OUT/tile" | cut -f1) on disk"

#!/usr/bin/env bash
# Tree heights of `treelobes tile` on real airborne crowns against the heights measured in the
# field (docs/tile.md, "Heights on real crowns"): every crown clip of ../shared/data/idtrees
# (NEON, about 5-10 pulses per m^2, clips of field-mapped crown polygons, not height-normalised)
# through `tile`, then for each clip the found tree holding the most points beside the
# labels.csv field height. Prints, per site and over all, the median and RMSE of found minus
# field height, how many lie within 5 m (a clip may not hold the tree it is labelled with) and
# the RMSE and mean absolute difference of those.
# Usage: bench/tile_field_heights.sh [OUT_DIR]   (default /tmp/treelobes_tile_field_heights)
# Environment: TREELOBES_BIN (default build/bin/treelobes), TREELOBES_REAL_DATA (default
# ../shared/data). Runs two clips at a time (GNU parallel, with a progress bar on stderr).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=$(realpath "${TREELOBES_BIN:-build/bin/treelobes}")
DATA=${TREELOBES_REAL_DATA:-../shared/data}
OUT=${1:-/tmp/treelobes_tile_field_heights}
LABELS="$DATA/idtrees/labels.csv"
[[ -x "$BIN" ]] || { echo "tile_field_heights: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
[[ -f "$LABELS" ]] || { echo "tile_field_heights: $LABELS not found (set TREELOBES_REAL_DATA)" >&2; exit 1; }
command -v parallel >/dev/null || { echo "tile_field_heights: GNU parallel not found (apt-get install parallel)" >&2; exit 1; }
mkdir -p "$OUT"
tail -n +2 "$LABELS" | cut -d, -f1 |
  parallel -j2 --bar --halt never "$BIN --log-level error tile $DATA/idtrees/{} --out $OUT/{//}_{/.} --overwrite --map-size 200 >/dev/null"
python3 - "$LABELS" "$OUT" <<'PY'
import csv, math, os, sys
labels, out = sys.argv[1], sys.argv[2]
rows, empty, failed = [], 0, []
for r in csv.DictReader(open(labels)):
    folder, name = os.path.split(r["file"])
    table = f"{out}/{folder}_{os.path.splitext(name)[0]}/trees.csv"
    if not os.path.exists(table):  # tile refused the clip (its message is above)
        failed.append(r["file"])
        continue
    trees = list(csv.DictReader(open(table)))
    if not trees:
        empty += 1
        continue
    found = max(trees, key=lambda t: int(t["points"]))
    rows.append((r["site"], float(found["height_m"]) - float(r["field_height_m"])))
print(f"{'crowns':<8} {'n':>4} {'median m':>9} {'RMSE m':>7} {'within 5 m':>10} {'RMSE there':>10} {'MAE there':>9}")
for site in sorted({s for s, _ in rows}) + ["all"]:
    d = sorted(e for s, e in rows if site in ("all", s))
    near = [e for e in d if abs(e) <= 5]
    rmse = lambda v: math.sqrt(sum(e * e for e in v) / len(v))
    print(f"{site:<8} {len(d):4d} {d[len(d) // 2]:+9.2f} {rmse(d):7.2f} {len(near):10d} {rmse(near):10.2f} {sum(abs(e) for e in near) / len(near):9.2f}")
print(f"clips with no tree (ground only): {empty}")
if failed:
    print(f"clips tile could not run on: {len(failed)} ({', '.join(failed[:5])}{', ...' if len(failed) > 5 else ''})")
PY

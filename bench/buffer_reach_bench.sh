#!/usr/bin/env bash
# How wide a tile buffer must be for the airborne segmentation to give the crowns of the uncut
# survey (docs/survey.md, "How far the airborne segmentation reaches"): lidR's MixedConifer.las
# (a real dense conifer plot, 90 x 90 m) processed whole with `tile --stand conifer`, then cut by
# `retile --size 45` and run as a batch with each buffer and the uncut run's return spacing; every
# merged tree is compared with the uncut run by its survey-wide id and its point count.
# Usage: bench/buffer_reach_bench.sh [WORK_DIR] [BUFFERS...]   (default /tmp/treelobes_buffer_reach,
# buffers 0 3.5 7 10 15). Environment: TREELOBES (default build/bin/treelobes), TREELOBES_REAL_DATA.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cli=${TREELOBES:-$root/build/bin/treelobes}
data=${TREELOBES_REAL_DATA:-$root/../shared/data}
work=$(realpath -m "${1:-/tmp/treelobes_buffer_reach}")
shift || true
buffers=("$@")
[[ ${#buffers[@]} -gt 0 ]] || buffers=(0 3.5 7 10 15)
plot="$data/lidr/MixedConifer.las"
[[ -f "$plot" ]] || { echo "buffer_reach_bench: $plot not found (set TREELOBES_REAL_DATA)" >&2; exit 1; }
options=(--stand conifer --map-size 200)
rm -rf "$work" && mkdir -p "$work" && cd "$work"

# Exit 3 (some small crowns fail the per-tree pipeline) is a finished run.
finished() { "$@" >/dev/null 2>&1 || [[ $? -eq 3 ]]; }
finished "$cli" --log-level error tile "$plot" --out uncut "${options[@]}"
# The tiles draw their CHM from the uncut run's return spacing (a batch otherwise measures it on
# its typical tile, docs/survey.md): the same CHM grid, so that only the buffer differs.
spacing=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['options']['chm']['return_spacing_m'])" uncut/summary.json)
options+=(--return-spacing "$spacing")
echo "return spacing of the uncut run: $spacing m"
"$cli" --log-level error retile "$plot" --size 45 --out tiles >/dev/null
echo "| buffer (m) | trees (uncut) | trees merged | same id | same id and points |"
echo "|---|---|---|---|---|"
for b in "${buffers[@]}"; do
  if [[ "$b" == 0 ]]; then
    finished "$cli" --log-level error batch tiles --out "batch_$b" "${options[@]}"
  else
    finished "$cli" --log-level error batch tiles --out "batch_$b" --buffer "$b" --tile-size 45 "${options[@]}"
  fi
  "$cli" --log-level error merge "batch_$b" --out "merged_$b" >/dev/null
  python3 - uncut/trees.csv "merged_$b/trees.csv" "$b" <<'PY'
import csv, sys
uncut = {r["global_id"]: r for r in csv.DictReader(open(sys.argv[1]))}
merged = list(csv.DictReader(open(sys.argv[2])))
same_id = [r for r in merged if r["global_id"] in uncut]
same_points = [r for r in same_id if r["points"] == uncut[r["global_id"]]["points"]]
print(f"| {sys.argv[3]} | {len(uncut)} | {len(merged)} | {len(same_id)} | {len(same_points)} |")
PY
done

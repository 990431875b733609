#!/bin/bash
# The buffer figures of docs/survey.md: one synthetic plot of PLOT x PLOT m with TREES trees, cut by
# `retile` into TILE m squares (crowns cross the edges), then
#   - one run of the uncut plot (the reference),
#   - a batch without a buffer (trees cut by an edge come out in pieces, one per tile),
#   - a batch with --buffer BUFFER, as 4 shards under GNU parallel -j1 and -j2 (--threads 1 each),
#     and as a Slurm job array of 4 tasks on a one-node cluster of this machine (when root),
# each merged; trees modelled and measured only, true trees absent, pieces and duplicates counted
# against the plot's labels (tree_id = the true id with --use-input-segmentation), the buffered
# merges compared with the reference (ids, bases) and with each other (bytes); the wall times of
# -j1 and -j2 with the load average of the machine around them. MODE=als runs the same with a
# fresh airborne segmentation instead of the plot's labels; COMPETITION=1 grows the plot with crown
# competition (`synth tile --competition`: crowns cut where a neighbour owns the canopy).
#   bench/survey_buffer_bench.sh [WORKDIR] [TREES] [PLOT] [TILE] [BUFFER]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cli=${TREELOBES:-$root/build/bin/treelobes}
work=$(realpath -m "${1:-/tmp/treelobes_survey_buffer_bench}")
trees=${2:-170} plot=${3:-100} tile=${4:-50} buffer=${5:-15}
if [[ "${MODE:-input}" == als ]]; then options="--mode als --map-size 200"; else options="--use-input-segmentation --map-size 200"; fi
synth_options=""
[[ "${COMPETITION:-0}" == 1 ]] && synth_options="--competition"
rm -rf "$work" && mkdir -p "$work" && cd "$work"

echo "plot ${plot} x ${plot} m, $trees trees ${synth_options}, ${tile} m tiles, ${buffer} m buffer, tile options: $options" >&2
"$cli" --log-level warn synth tile --trees "$trees" --size "$plot" --seed 21 --pulse-density 20 --max-leaves 2000 \
  --origin 500000 5400000 300 $synth_options --out plot >/dev/null
"$cli" --log-level warn retile plot/tile.las --size "$tile" --out tiles >/dev/null

load() { cut -d' ' -f1-3 /proc/loadavg; }
seconds() { local start end; start=$(date +%s.%N); "$@" >/dev/null 2>&1 || true; end=$(date +%s.%N); python3 -c "print(round($end - $start, 1))"; }
merge() { "$cli" --log-level error merge "$2" --out "$1" >/dev/null 2>&1 || true; }

t_single=$(seconds "$cli" --log-level error --threads 1 tile plot/tile.las --out single $options)
merge single_merged single
t_nobuffer=$(seconds "$cli" --log-level error --threads 1 batch tiles --out nobuffer $options)
merge nobuffer_merged nobuffer
load_j1_before=$(load)
t_j1=$(seconds parallel -j1 "$cli" --log-level error --threads 1 batch tiles --out j1 --shard {}/4 --buffer "$buffer" --tile-size "$tile" $options ::: 0 1 2 3)
load_j1_after=$(load)
merge j1_merged j1
load_j2_before=$(load)
t_j2=$(seconds parallel -j2 "$cli" --log-level error --threads 1 batch tiles --out j2 --shard {}/4 --buffer "$buffer" --tile-size "$tile" $options ::: 0 1 2 3)
load_j2_after=$(load)
merge j2_merged j2
# The same batch as a Slurm job array on a one-node cluster of this machine (needs root, slurm-wlm, munge).
slurm_ran=no
if command -v slurmctld >/dev/null && [[ $(id -u) == 0 ]]; then
  mkdir -p jobs
  PATH="$(dirname "$cli"):$PATH" "$root/tests/survey/local_slurm_cluster.sh" "$work/cluster" sh -c \
    "cd '$work/jobs' && sbatch --array=0-3 --wait --mem=1G --export=ALL,TILES='$work/tiles',OUT='$work/slurm',MAX_MEMORY=900M,TILE_OPTIONS='--buffer $buffer --tile-size $tile $options' '$root/scripts/slurm/batch.sbatch' >/dev/null" >/dev/null 2>&1 || true
  merge slurm_merged slurm
  slurm_ran=yes
fi

# Detection on the uncut plot against its labels (airborne mode: the segmentation the tiles use).
if [[ "${MODE:-input}" == als ]]; then
  "${SEGMENT_EVAL:-$root/build/bin/segment_eval}" plot/tile.las --mode als --reference treeID | python3 -c '
import json, sys
s = json.load(sys.stdin)["score"]
print("uncut plot, airborne segmentation against the labels (trees > 5 m, half-of-points rule): %d true, %d found, %d matched, F1 %.3f" % (s["reference_trees"], s["found_trees"], s["matched"], s["f1"]))'
fi
python3 - "$plot" "$tile" "$t_single" "$t_nobuffer" "$t_j1" "$t_j2" "$load_j1_before" "$load_j1_after" "$load_j2_before" "$load_j2_after" "$options" "$slurm_ran" <<'PY'
import csv, filecmp, glob, json, math, os, struct, sys
from collections import Counter
plot, tile = float(sys.argv[1]), float(sys.argv[2])
t_single, t_nobuffer, t_j1, t_j2 = (float(v) for v in sys.argv[3:7])
loads = sys.argv[7:11]
truth = list(csv.DictReader(open("plot/truth.csv")))
per_square = Counter((math.floor(float(t["x"]) / tile), math.floor(float(t["y"]) / tile)) for t in truth)
inner_edges = [k * tile for k in range(1, int(plot / tile))]  # from the plot's corner 500000, 5400000
def crosses(t):
    reach = float(t["crown_diameter_m"]) / 2
    return any(abs(float(t["x"]) - 500000 - e) < reach or abs(float(t["y"]) - 5400000 - e) < reach for e in inner_edges)
crossing = sum(1 for t in truth if crosses(t))
points = sum(struct.unpack_from("<Q", open(f, "rb").read(255), 247)[0] for f in glob.glob("tiles/*.las"))
def rows(folder):
    return list(csv.DictReader(open(folder + "/trees.csv")))
single, nobuffer, j1, j2 = rows("single_merged"), rows("nobuffer_merged"), rows("j1_merged"), rows("j2_merged")
labels = "--use-input-segmentation" in sys.argv[11]  # tree_id is the true id only with the plot's labels
def repeated(table):
    if not labels:
        return "n/a", "n/a"
    count = Counter(r["tree_id"] for r in table)
    return sum(1 for c in count.values() if c > 1), sum(c - 1 for c in count.values() if c > 1)
by_id = {r["global_id"]: r for r in single}
print(f"true trees {len(truth)}; per {tile:.0f} m square: {sorted(per_square.values(), reverse=True)[:4]}; crowns across an inner edge: {crossing}")
print(f"points in the tiles: {points}; tiles: {len(glob.glob('tiles/*.las'))}")
def absent(table):  # true trees without a row (with labels: trees no pulse reached, or lost)
    return len(truth) - len({r["tree_id"] for r in table}) if labels else "n/a"
print("| run | trees merged | modelled / measured only | true trees absent | true trees in pieces | extra pieces | same id and base (1 cm) as the uncut plot |")
print("|---|---|---|---|---|---|---|")
for name, table in [("uncut plot, one tile run", single), ("tiles, no buffer", nobuffer), ("tiles, buffer, parallel -j1", j1), ("tiles, buffer, parallel -j2", j2)]:
    cut, extra = repeated(table)
    ids = sum(1 for r in table if r["global_id"] in by_id and all(abs(float(r[a]) - float(by_id[r["global_id"]][a])) <= 0.01 for a in "xyz"))
    modelled = sum(1 for r in table if r["model"] == "ok")
    print(f"| {name} | {len(table)} | {modelled} / {len(table) - modelled} | {absent(table)} | {cut} | {extra} | {ids} |")
merged_files = ["trees.csv", "trees.geojson", "survey.forest", "summary.json"]
def same_bytes(a, b):
    return all(filecmp.cmp(f"{a}/{f}", f"{b}/{f}", shallow=False) for f in merged_files)
print(f"-j1 and -j2 merges byte-identical: {same_bytes('j1_merged', 'j2_merged')}")
if sys.argv[12] == "yes":
    slurm = rows("slurm_merged") if os.path.exists("slurm_merged/trees.csv") else []
    print(f"Slurm job array (--array=0-3): {len(slurm)} trees merged; byte-identical to -j1: {bool(slurm) and same_bytes('j1_merged', 'slurm_merged')}")
else:
    print("Slurm job array: not run (needs root, slurm-wlm and munge)")
print("| run | wall time (s) | load average before | after |")
print("|---|---|---|---|")
print(f"| uncut plot, tile --threads 1 | {t_single} | | |")
print(f"| batch without buffer, --threads 1 | {t_nobuffer} | | |")
print(f"| buffer, parallel -j1, 4 shards | {t_j1} | {loads[0]} | {loads[1]} |")
print(f"| buffer, parallel -j2, 4 shards | {t_j2} | {loads[2]} | {loads[3]} |")
print(f"| ratio -j2 / -j1 | {t_j2 / t_j1:.2f} | | |")
PY

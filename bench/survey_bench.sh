#!/bin/bash
# The figures of docs/survey.md: a synthetic survey of TILES tiles side by side (TREES trees each,
# SIZE m squares), run as one batch, as 4 shards one after the other, with GNU parallel, and as a
# Slurm job array on a one-node cluster of this machine (root; tests/survey/local_slurm_cluster.sh);
# every run merged and compared byte by byte with the single run; then the wall time of the
# whole batch with `parallel -j1` and `-j2` (4 shards each).
#   bench/survey_bench.sh [WORKDIR] [TILES] [TREES] [SIZE]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cli=${TREELOBES:-$root/build/bin/treelobes}
work=$(realpath -m "${1:-/tmp/treelobes_survey_bench}")
tiles_n=${2:-16} trees=${3:-12} size=${4:-30}
options="--use-input-segmentation --map-size 200"
rm -rf "$work" && mkdir -p "$work/tiles"
cd "$work"

echo "synthetic survey: $tiles_n tiles x $trees trees, ${size} m squares" >&2
side=$(python3 -c "import math; print(math.ceil(math.sqrt($tiles_n)))")
for ((i = 0; i < tiles_n; i++)); do
  x=$((500000 + (i % side) * size)) y=$((5400000 + (i / side) * size))
  "$cli" --log-level warn synth tile --trees "$trees" --size "$size" --seed $((100 + i)) --pulse-density 20 --max-leaves 2000 \
    --origin "$x" "$y" 300 --out "synth_$i" >/dev/null
  mv "synth_$i/tile.las" "tiles/$(printf 't_%02d' "$i").las"
  rm -rf "synth_$i"
done
points=$(python3 -c "import glob, struct
print(sum(struct.unpack_from('<Q', open(f, 'rb').read(255), 247)[0] for f in glob.glob('tiles/*.las')))")  # LAS 1.4 point count

seconds() { local start=$SECONDS; "$@" >/dev/null; echo $((SECONDS - start)); }
batch() { "$cli" --log-level warn batch tiles --out "$1" "${@:2}" $options >/dev/null; }
merge() { "$cli" --log-level warn merge "${@:2}" --out "$1" >/dev/null || true; }

t_single=$(seconds batch single)
merge single_merged single
for i in 0 1 2 3; do batch shards --shard "$i/4"; done
merge shards_merged shards
t_j1=$(seconds parallel -j1 "$cli" --log-level warn --threads 1 batch tiles --out par1 --shard {}/4 $options ::: 0 1 2 3 >/dev/null)
merge par1_merged par1
t_j2=$(seconds parallel -j2 "$cli" --log-level warn --threads 1 batch tiles --out par2 --shard {}/4 $options ::: 0 1 2 3 >/dev/null)
merge par2_merged par2
mkdir -p jobs
PATH="$(dirname "$cli"):$PATH" "$root/tests/survey/local_slurm_cluster.sh" "$work/cluster" sh -c \
  "cd '$work/jobs' && sbatch --array=0-3 --wait --mem=1G --export=ALL,TILES='$work/tiles',OUT='$work/slurm',MAX_MEMORY=900M,TILE_OPTIONS='$options' '$root/scripts/slurm/batch.sbatch' >/dev/null"
merge slurm_merged slurm

same() { cmp -s "single_merged/$2" "$1/$2" && echo same || echo DIFFERENT; }
trees_merged=$(python3 -c "import json; print(json.load(open('single_merged/summary.json'))['trees'])")
echo "| run | trees.csv | trees.geojson | survey.forest | summary.json |"
echo "|---|---|---|---|---|"
for run in shards_merged par1_merged par2_merged slurm_merged; do
  echo "| $run | $(same $run trees.csv) | $(same $run trees.geojson) | $(same $run survey.forest) | $(same $run summary.json) |"
done
echo
echo "tiles $tiles_n, points $points, trees merged $trees_merged"
echo "| run | wall time (s) |"
echo "|---|---|"
echo "| one batch, all threads | $t_single |"
echo "| parallel -j1, 4 shards, --threads 1 | $t_j1 |"
echo "| parallel -j2, 4 shards, --threads 1 | $t_j2 |"
python3 -c "print('| ratio j2/j1 | %.2f |' % ($t_j2 / max($t_j1, 1)))"

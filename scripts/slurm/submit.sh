#!/bin/bash
# Submits a survey to Slurm: the batch as a job array of SHARDS tasks, then the merge as a job
# that starts when every task has ended (docs/survey.md).
#   scripts/slurm/submit.sh TILES OUT SHARDS [tile options...]
# e.g. scripts/slurm/submit.sh 'tiles/*.las' runs/ 32 --mode als
# The merged survey lands in OUT/merged (trees.csv, trees.geojson, survey.forest, summary.json).
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 TILES OUT SHARDS [tile options...]" >&2
  exit 1
fi
tiles=$1 out=$2 shards=$3
shift 3
here=$(dirname "$(realpath "$0")")
array=$(sbatch --parsable --array="0-$((shards - 1))" \
  --export=ALL,TILES="$tiles",OUT="$out",TILE_OPTIONS="$*" "$here/batch.sbatch")
array=${array%%;*}  # "jobid;cluster" on multi-cluster setups
merge=$(sbatch --parsable --dependency="afterany:$array" --job-name=treelobes-merge --time=01:00:00 --mem=8G \
  --output=treelobes-merge-%j.log --wrap "treelobes merge '$out' --out '$out/merged'")
echo "batch array $array ($shards tasks), merge job ${merge%%;*} after it"

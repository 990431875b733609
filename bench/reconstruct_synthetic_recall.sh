#!/usr/bin/env bash
# Branch recall on synthetic TLS trees with ground truth (target: mean recall >= 0.9 for
# branches thicker than 2 cm). For each of the 12 species of config/species.yaml: one TLS scan
# (`treelobes synth tree --scanner tls`, modest height and angular step so scans stay at a few
# 100k points), `treelobes reconstruct --species`, then `treelobes eval skeleton` against the
# true skeleton. Prints per species: points, branch recall / precision (counts), skeleton ->
# reference and reference -> skeleton median distance, then the mean recall and precision.
# Usage: bench/reconstruct_synthetic_recall.sh [OUT_DIR]   (default /tmp/treelobes_synthetic_recall)
# Environment: TREELOBES_BIN (default build/bin/treelobes), SEED (default 1), HEIGHT (default 8 m,
# capped to each species' range), ANGULAR_STEP (default 0.2 degrees: coarse enough for a few 100k points, fine enough that a 2 cm branch 10 m away is hit every 3.5 cm), THREADS (default 0 = all),
# SYNTH_ARGS (extra `synth tree` options, e.g. "--no-leaves" to score the skeleton without the
# leaf clutter that TLS scans of leafy trees carry; no wood/leaf separation runs before reconstruct).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
OUT=${1:-/tmp/treelobes_synthetic_recall}
SEED=${SEED:-1}
HEIGHT=${HEIGHT:-8}
ANGULAR_STEP=${ANGULAR_STEP:-0.2}
THREADS=${THREADS:-0}
SYNTH_ARGS=${SYNTH_ARGS:-}
[[ -x "$BIN" ]] || { echo "reconstruct_synthetic_recall: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
mkdir -p "$OUT"
SPECIES=$(sed -n 's/^  - name: *//p' config/species.yaml)

printf '%-20s %8s %16s %16s %9s %9s\n' species points recall precision s-\>r_med r-\>s_med
for s in $SPECIES; do
  # Height: HEIGHT clamped into the species' height_m range.
  h=$(python3 - "$s" "$HEIGHT" <<'PY'
import re, sys
text = open("config/species.yaml").read()
block = text.split(f"- name: {sys.argv[1]}\n", 1)[1]
lo, hi = map(float, re.search(r"height_m: \[([\d.]+), ([\d.]+)\]", block).groups())
print(min(max(float(sys.argv[2]), lo), hi))
PY
)
  dir="$OUT/$s"
  "$BIN" --threads "$THREADS" --log-level error synth tree --species "$s" --seed "$SEED" --scanner tls --height "$h" \
    --angular-step "$ANGULAR_STEP" --ground-margin 0 $SYNTH_ARGS --no-mesh --overwrite --out "$dir" >"$dir.synth.log" 2>&1
  scan="$dir/${s}_${SEED}.las"
  "$BIN" --threads "$THREADS" --log-level error reconstruct "$scan" --species "$s" --out "$dir/rec" --overwrite >"$dir.rec.log" 2>&1
  "$BIN" --log-level error --json eval skeleton --skeleton "$dir/rec/${s}_${SEED}_skeleton.ply" \
    --reference "$dir/${s}_${SEED}_skeleton.ply" >"$dir/eval.json"
  points=$(sed -n 's/.*tls scan: \([0-9]*\) points.*/\1/p' "$dir.synth.log")
  python3 - "$s" "$points" "$dir/eval.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
b = j["branches"]
print(f'{sys.argv[1]:<20} {sys.argv[2]:>8} {b["recall"]:6.3f} {b["detected"]:>4}/{b["reference_branches"]:<4} '
      f'{b["precision"]:6.3f} {b["correct"]:>4}/{b["skeleton_branches"]:<4} '
      f'{j["skeleton_to_reference"]["median"]:9.4f} {j["reference_to_skeleton"]["median"]:9.4f}')
PY
done | tee "$OUT/table.txt"
python3 - "$OUT/table.txt" <<'PY'
import sys
rows = [line.split() for line in open(sys.argv[1]) if line.strip()]
recall = [float(r[2]) for r in rows]
precision = [float(r[4]) for r in rows]
print(f"mean over {len(rows)} species: recall {sum(recall) / len(rows):.3f}, precision {sum(precision) / len(rows):.3f}")
PY

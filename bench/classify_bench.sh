#!/usr/bin/env bash
# Species classification benchmark: synthetic labelled scans of the 12 species (TLS and
# ALS), shape features, the paper's protocol (100 random 50/50 splits per species), JointBoost
# against XGBoost on the same features and splits, the site split (TLS trees vs ALS trees), and
# spatial voting in grouped and mixed plantings. Prints the figures; reports go to OUT/report_*.
# Usage: bench/classify_bench.sh [OUT_DIR] (default /tmp/treelobes_classify_bench)
# Environment: PER_SPECIES (trees per species and scanner, default 20), SPLITS (default 100).
set -euo pipefail
cd "$(dirname "$0")/.."
# XGBoost (libgomp) spins while waiting for work by default: on shared cores that made its
# training 10x slower (50 s instead of 5 s per split on 2 busy cores). Passive waiting is fair to it.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
BIN=${TREELOBES_BIN:-build/bin/treelobes}
OUT=${1:-/tmp/treelobes_classify_bench}
PER_SPECIES=${PER_SPECIES:-20}
SPLITS=${SPLITS:-100}
[[ -x "$BIN" ]] || { echo "classify_bench: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
BIN=$(realpath "$BIN")
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)  # absolute: the features run inside the dataset folders, which may be symlinks

# Datasets are kept between runs (synth keeps finished trees).
"$BIN" --log-level warn synth dataset --per-species "$PER_SPECIES" --seed 11 --max-leaves 8000 --angular-step 0.2 --out "$OUT/tls"
"$BIN" --log-level warn synth dataset --per-species "$PER_SPECIES" --seed 12 --scanner als --pulse-density 20 --sub-rays 7 \
  --max-leaves 8000 --out "$OUT/als"

# Feature tables are cached, keyed by the feature catalogue (names and descriptions): a change of
# the feature code that shows in docs/features.md recomputes them.
KEY=$("$BIN" classify features --list | sha1sum | cut -d' ' -f1)
features() {  # features of one dataset, ids prefixed with the dataset name (as evaluate does)
  local name=$1
  [[ -s "$OUT/${name}_features.csv" && "$(cat "$OUT/${name}_features.key" 2>/dev/null)" == "$KEY" ]] && return
  (cd "$OUT/$name" && "$BIN" --log-level warn --json classify features */*.las --out "$OUT/${name}_features_raw.csv") \
    > "$OUT/${name}_features.json"
  python3 - "$OUT/${name}_features_raw.csv" "$name" "$OUT/${name}_features.csv" <<'PY'
import sys
src, prefix, dst = sys.argv[1:]
lines = open(src).read().splitlines()
with open(dst, "w") as out:
    out.write(lines[0] + "\n")
    for line in lines[1:]:
        out.write(prefix + "/" + line + "\n")
PY
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(f'{sys.argv[2]}: {d[\"trees\"]} trees, {d[\"points\"]} points, ' \
    f'{d[\"cpu_seconds_per_tree\"]:.2f} s CPU per tree with reading (mean {d[\"points\"]/d[\"trees\"]:.0f} points), {d[\"seconds\"]:.0f} s wall')" \
    "$OUT/${name}_features.json" "$name"
  echo "$KEY" > "$OUT/${name}_features.key"
}
features tls
features als
{ head -1 "$OUT/tls_features.csv"; tail -n +2 "$OUT/tls_features.csv"; tail -n +2 "$OUT/als_features.csv"; } > "$OUT/features.csv"
# Site groups: the scanner (train on TLS trees, test on ALS trees and the other way round).
python3 - "$OUT" <<'PY'
import sys
out = sys.argv[1]
with open(f"{out}/labels.csv", "w") as f:
    f.write("id,species,site\n")
    for name in ("tls", "als"):
        lines = open(f"{out}/{name}/labels.csv").read().splitlines()
        for line in lines[1:]:
            cols = line.split(",")
            f.write(f"{name}/{cols[0]},{cols[1]},{name}\n")
PY
# A dataset folder whose labels.csv carries the site column, for `classify evaluate`.
mkdir -p "$OUT/mixed"
cp "$OUT/labels.csv" "$OUT/mixed/labels.csv"

summary() {
  python3 - "$1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1] + "/summary.json"))
for name, c in d["classifiers"].items():
    r = c["random_splits"]
    line = (f"  {name:10s} rate {100*r['average_recognition_rate']:.1f} %  trees {100*r['tree_accuracy']:.1f} %  "
            f"confident {100*r['confident_fraction']:.0f} % of trees at {100*r['confident_accuracy']:.1f} %, "
            f"others {100*r['unconfident_accuracy']:.1f} %  train {r['train_seconds_mean']:.3f} s/split "
            f"({r.get('cpu_seconds_mean', 0):.2f} s CPU with prediction)  rounds {r['mean_rounds']:.0f}")
    if "voted_average_recognition_rate" in r:
        line += f"  voted {100*r['voted_average_recognition_rate']:.1f} %"
    if "site_split" in c:
        line += f"  site split {100*c['site_split']['average_recognition_rate']:.1f} %"
    if "group_accuracy" in r:
        line += "  per scanner: " + ", ".join(f"{g} {100*a:.1f} %" for g, a in r["group_accuracy"].items())
    print(line)
print(f"  ({d['seconds']:.0f} s for the whole evaluation)")
PY
}

# One run gives the protocol's figures, XGBoost, the site split and voting in grouped plantings
# (voting only re-reads the probabilities, so the figures without voting are those of any layout);
# a second run, JointBoost only, votes in mixed plantings.
echo "== $SPLITS random 50/50 splits, TLS + ALS, site split by scanner, voting in grouped plantings (8 m spacing, 25 m radius) =="
/usr/bin/time -f "  (wall %e s, CPU %U s user + %S s system)" \
  "$BIN" --log-level warn classify evaluate "$OUT/mixed" --features "$OUT/features.csv" --splits "$SPLITS" --layout grouped \
  --out "$OUT/report_grouped" > /dev/null
summary "$OUT/report_grouped"
echo "== voting, mixed planting (JointBoost only) =="
"$BIN" --log-level warn classify evaluate "$OUT/mixed" --features "$OUT/features.csv" --splits "$SPLITS" --no-site-split --no-xgboost \
  --layout mixed --out "$OUT/report_mixed" > /dev/null
summary "$OUT/report_mixed"
# The protocol's time target ("the full 100-split evaluation of 480 trees in a few minutes"):
# JointBoost alone, grouped voting, no site split (the splits run side by side on all cores).
echo "== time of the protocol, JointBoost only =="
/usr/bin/time -f "  (wall %e s, CPU %U s user + %S s system)" \
  "$BIN" --log-level warn classify evaluate "$OUT/mixed" --features "$OUT/features.csv" --splits "$SPLITS" --no-site-split --no-xgboost \
  --layout grouped --out "$OUT/report_jointboost" > /dev/null
summary "$OUT/report_jointboost"
echo "per-species rates: $OUT/report_grouped/per_species.csv, per tree: $OUT/report_grouped/per_tree_JointBoost.csv, confusion: $OUT/report_grouped/confusion_JointBoost.png"

#!/usr/bin/env bash
# Species from real airborne crowns: the classifier on the IDTReeS crowns (NEON, 593 trees, 13 taxa,
# two sites) in ../shared/data/idtrees, the paper's protocol (random 50/50 splits) with JointBoost
# and XGBoost on the airborne feature group, spatial voting among the real neighbours, and the
# bounds measured for docs/classify.md: a learning curve (30 / 50 / 80 % training) and the same
# protocol with all feature groups. Prints the figures; reports go to OUT/report_*.
# Usage: bench/classify_idtrees.sh [OUT_DIR] (default /tmp/treelobes_classify_idtrees)
# Environment: SPLITS (default 100), TREELOBES_REAL_DATA (default ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
BIN=${TREELOBES_BIN:-build/bin/treelobes}
DATA=${TREELOBES_REAL_DATA:-../shared/data}/idtrees
OUT=${1:-/tmp/treelobes_classify_idtrees}
SPLITS=${SPLITS:-100}
[[ -x "$BIN" ]] || { echo "classify_idtrees: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
[[ -f "$DATA/labels.csv" ]] || { echo "classify_idtrees: $DATA/labels.csv not found (set TREELOBES_REAL_DATA)" >&2; exit 1; }
mkdir -p "$OUT"

summary() {
  python3 - "$1" "$2" <<'PY'
import json, sys
d = json.load(open(sys.argv[1] + "/summary.json"))
for name, c in d["classifiers"].items():
    r = c["random_splits"]
    g = r.get("genus", {})
    line = (f"  {sys.argv[2]:28s} {name:10s} rate {100*r['average_recognition_rate']:.1f} %  trees {100*r['tree_accuracy']:.1f} %  "
            f"macro-F1 {r['macro_f1']:.3f}  kappa {r['kappa']:.3f}")
    if g:
        line += f"  genus trees {100*g['tree_accuracy']:.1f} % rate {100*g['average_recognition_rate']:.1f} %"
    if "voted_average_recognition_rate" in r:
        line += f"  voted rate {100*r['voted_average_recognition_rate']:.1f} % trees {100*r['voted_tree_accuracy']:.1f} %"
    if "group_accuracy" in r:
        line += "  per site: " + ", ".join(f"{s} {100*a:.1f} %" for s, a in r["group_accuracy"].items())
    print(line)
if "removed" in d:
    print("  removed before the features:", d["removed"])
if "site_split_note" in d:
    print("  site split", d["site_split_note"])
PY
}

echo "== $SPLITS random 50/50 splits, airborne group (features computed, voting among the real neighbours) =="
/usr/bin/time -f "  (wall %e s, CPU %U s user + %S s system)" \
  "$BIN" --log-level warn classify evaluate "$DATA" --groups airborne --splits "$SPLITS" --out "$OUT/report_airborne" > /dev/null
summary "$OUT/report_airborne" "airborne, class weights"
FEATURES="$OUT/report_airborne/features.csv"
"$BIN" --log-level warn classify evaluate "$DATA" --features "$FEATURES" --groups airborne --splits "$SPLITS" --no-class-weights \
  --no-xgboost --out "$OUT/report_unweighted" > /dev/null
summary "$OUT/report_unweighted" "airborne, no class weights"
"$BIN" --log-level warn classify evaluate "$DATA" --features "$FEATURES" --groups airborne --splits "$SPLITS" --level genus \
  --out "$OUT/report_genus" > /dev/null
summary "$OUT/report_genus" "genus model"
echo "== learning curve (JointBoost, airborne group) =="
for fraction in 0.3 0.8; do
  "$BIN" --log-level warn classify evaluate "$DATA" --features "$FEATURES" --groups airborne --splits "$SPLITS" --no-xgboost \
    --train-fraction "$fraction" --out "$OUT/report_train_$fraction" > /dev/null
  summary "$OUT/report_train_$fraction" "training share $fraction"
done
echo "== all feature groups (shape groups too; 20 splits: they cost ~10x the CPU) =="
"$BIN" --log-level warn classify evaluate "$DATA" --features "$FEATURES" --splits 20 --out "$OUT/report_all_groups" > /dev/null
summary "$OUT/report_all_groups" "all groups"

#!/usr/bin/env python3
"""Per-tree accuracy of `treelobes tile` against the truth of `treelobes synth tile`.

Usage: tile_accuracy.py TRUTH_CSV RUN_DIR [TRUTH_CSV RUN_DIR ...]

RUN_DIR is a `tile --out` directory whose points.las has been converted to points.csv
(`treelobes convert RUN_DIR/points.las --out RUN_DIR/points.csv`). True trees taller than 5 m
are matched to found trees two ways: (1) by points, the issue's rule: each holds at least half
of the other's points (points.csv carries the found treeID and the input's true one as
treeID_input); (2) the found stem nearest within 2 m (one-to-one, nearest first). A found tree
that merges several crowns matches no true tree by points, while by distance it pairs with
whichever stem lies nearest; (1) is therefore the fair measure of the per-tree measures.

For each pair of arguments it prints one line (named after RUN_DIR when there are several): matched trees, height RMSE and bias, stem
position RMS, the RMSE of the ground at the stem (found z minus true z: the stem position's
share of the height error on a slope) and, over fitted DBHs, the DBH RMSE. With several pairs
a last line pools the trees of all of them."""
import csv
import math
import os
import sys
from collections import Counter


def read_matches(truth_csv, run_dir):
    truth = {r["tree_id"]: r for r in csv.DictReader(open(truth_csv)) if float(r["height_m"]) > 5}
    found = {r["tree_id"]: r for r in csv.DictReader(open(f"{run_dir}/trees.csv"))}
    pairs = sorted((math.hypot(float(t["x"]) - float(f["x"]), float(t["y"]) - float(f["y"])), i, j)
                   for i, t in truth.items() for j, f in found.items())
    used_t, used_f, by_distance = set(), set(), []
    for d, i, j in pairs:
        if d > 2.0 or i in used_t or j in used_f:
            continue
        used_t.add(i)
        used_f.add(j)
        by_distance.append((truth[i], found[j]))
    rows = csv.reader(open(f"{run_dir}/points.csv"))
    header = next(rows)
    found_column = header.index("treeID")  # with --use-input-segmentation the true ids are the found ones
    true_column = header.index("treeID_input") if "treeID_input" in header else found_column
    shared, found_points, true_points = Counter(), Counter(), Counter()
    for row in rows:
        f, t = str(int(float(row[found_column]))), str(int(float(row[true_column])))
        found_points[f] += f != "0"
        true_points[t] += t != "0"
        if f != "0" and t != "0":
            shared[(f, t)] += 1
    by_points = [(truth[t], found[f]) for (f, t), n in shared.items()
                 if t in truth and f in found and 2 * n >= found_points[f] and 2 * n >= true_points[t]]
    return len(truth), by_points, by_distance


def rmse(values):
    return math.sqrt(sum(x * x for x in values) / len(values)) if values else float("nan")


def mean(values):
    return sum(values) / len(values) if values else float("nan")


def figures(matches, how):
    dh = [float(f["height_m"]) - float(t["height_m"]) for t, f in matches]
    dp = [math.hypot(float(f["x"]) - float(t["x"]), float(f["y"]) - float(t["y"])) for t, f in matches]
    dz = [float(f["z"]) - float(t["z"]) for t, f in matches]
    dd = [float(f["dbh_m"]) - float(t["dbh_m"]) for t, f in matches if f["dbh_m"]]
    ok = sum(1 for t, f in matches if f["dbh_quality"] == "ok")
    dbh = f"DBH fitted for {len(dd)} ({ok} ok), DBH RMSE {100 * rmse(dd):.1f} cm" if dd else "no DBH fitted"
    return (f"{len(matches)} matched {how}: height RMSE {rmse(dh):.2f} m (bias {mean(dh):+.2f}), "
            f"position RMS {rmse(dp):.2f} m, ground RMSE {rmse(dz):.2f} m, {dbh}")


def main(arguments):
    if len(arguments) < 2 or len(arguments) % 2:
        sys.exit(__doc__.split("\n\n")[1])
    total, all_points, all_distance = 0, [], []
    for truth_csv, run_dir in zip(arguments[0::2], arguments[1::2]):
        count, by_points, by_distance = read_matches(truth_csv, run_dir)
        total += count
        all_points += by_points
        all_distance += by_distance
        label = f"{os.path.basename(os.path.normpath(run_dir))}: " if len(arguments) > 2 else ""
        print(f"{label}{count} true trees > 5 m; {figures(by_points, 'by points')}; {figures(by_distance, 'within 2 m')}")
    if len(arguments) > 2:
        print(f"all: {total} true trees > 5 m; {figures(all_points, 'by points')}; {figures(all_distance, 'within 2 m')}")


if __name__ == "__main__":
    main(sys.argv[1:])

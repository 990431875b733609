#!/usr/bin/env bash
# Skeleton reconstruction figures (docs/reconstruct.md), all from whole-process runs of the CLI:
#   1. accuracy on the real scans with references (WoodSKE HS/OR/SW, aRchi tree1 + TreeQSM):
#      skeleton -> reference and reference -> skeleton median/p95 (1 cm samples), total-length
#      ratio, trunk-radius error, connected components (`treelobes eval skeleton`);
#   2. wall time and peak memory (/usr/bin/time -v) per real scan, with the quality flags
#      (adtree/house.xyz must come out as "not_a_tree");
#   3. a scaling table on synthetic branching clouds of 100k, 300k, 1M and 3M points.
# Usage: bench/reconstruct_bench.sh [OUT_DIR]   (default /tmp/treelobes_reconstruct_bench)
# Environment: TREELOBES_BIN (default build/bin/treelobes), TREELOBES_REAL_DATA (default
# ../shared/data), SIZES (default "100000 300000 1000000 3000000"), THREADS (default 0 = all).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${TREELOBES_BIN:-build/bin/treelobes}
DATA=${TREELOBES_REAL_DATA:-../shared/data}
OUT=${1:-/tmp/treelobes_reconstruct_bench}
SIZES=${SIZES:-"100000 300000 1000000 3000000"}
THREADS=${THREADS:-0}
[[ -x "$BIN" ]] || { echo "reconstruct_bench: $BIN not found (build first or set TREELOBES_BIN)" >&2; exit 1; }
[[ -d "$DATA" ]] || { echo "reconstruct_bench: real data folder $DATA not found (set TREELOBES_REAL_DATA)" >&2; exit 1; }
[[ -x /usr/bin/time ]] || { echo "reconstruct_bench: /usr/bin/time missing (apt-get install time)" >&2; exit 1; }
mkdir -p "$OUT"

# Runs one reconstruction under /usr/bin/time; prints "wall_seconds peak_MB cpu_seconds" (CPU =
# user + system: the figure to compare when the machine is shared and wall time is inflated).
timed_reconstruct() {
  local input=$1 out=$2
  /usr/bin/time -v "$BIN" --threads "$THREADS" --log-level error reconstruct "$input" --out "$out" --overwrite \
    >"$out.log" 2>"$out.time" || { echo "reconstruct failed on $input (see $out.time)" >&2; return 1; }
  python3 - "$out.time" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", text).group(1)
seconds = sum(float(part) * 60 ** i for i, part in enumerate(reversed(wall.split(":"))))
peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024
cpu = sum(float(re.search(rf"{kind} time \(seconds\): (\S+)", text).group(1)) for kind in ("User", "System"))
print(f"{seconds:.2f} {peak:.1f} {cpu:.2f}")
PY
}

stem_of() { local name; name=$(basename "$1"); echo "${name%.*}"; }

echo "== 1. accuracy against the references (metres; peer = Delaunay+Dijkstra, skeleton->reference) =="
printf "%-24s %8s %8s %8s %8s %9s %10s %6s  %s\n" scan sk_med sk_p95 ref_med ref_p95 len_ratio trunk_err pieces "peer med/p95"
while read -r cloud reference peer; do
  [[ -f "$DATA/$cloud" && -f "$DATA/$reference" ]] || { echo "$cloud: missing, skipped"; continue; }
  out="$OUT/accuracy"
  mkdir -p "$out"
  "$BIN" --threads "$THREADS" --log-level error reconstruct "$DATA/$cloud" --out "$out" --overwrite >/dev/null
  skeleton="$out/$(stem_of "$cloud")_skeleton.ply"
  "$BIN" --log-level error eval skeleton --skeleton "$skeleton" --reference "$DATA/$reference" --json >"$out/$(stem_of "$cloud")_eval.json"
  python3 - "$out/$(stem_of "$cloud")_eval.json" "$cloud" "$peer" <<'PY'
import json, sys
e = json.load(open(sys.argv[1]))
fmt = lambda v, spec: "-" if v is None else format(v, spec)
print(f"{sys.argv[2]:<24} {e['skeleton_to_reference']['median']:8.4f} {e['skeleton_to_reference']['p95']:8.4f} "
      f"{e['reference_to_skeleton']['median']:8.4f} {e['reference_to_skeleton']['p95']:8.4f} "
      f"{fmt(e['length_ratio'], '9.3f')} {fmt(e['trunk_radius_error'], '+10.3f')} {e['components']:6d}  {sys.argv[3]}")
PY
done <<'LIST'
woodske/HS_wood.csv woodske/HS_reference_skeleton.txt 0.036/0.204
woodske/OR_wood.csv woodske/OR_reference_skeleton.txt 0.013/0.107
woodske/SW_wood.csv woodske/SW_reference_skeleton.txt 0.035/0.189
archi/tree1_points.las archi/tree1_treeqsm_cylinders.txt 0.051/0.940
LIST

echo
echo "== 2. real scans: whole-process wall time and peak memory (--threads $THREADS) =="
printf "%-26s %9s %9s %9s %8s  %s\n" scan points seconds cpu_s peak_MB flags
for cloud in adtree/tree1.xyz adtree/tree7.xyz adtree/tree13.xyz adtree/Lille_11.xyz adtree/ahn3_delft.xyz adtree/house.xyz \
             woodske/HS_wood.csv woodske/OR_wood.csv woodske/SW_wood.csv archi/tree1_points.las treels/pine.las; do
  [[ -f "$DATA/$cloud" ]] || { echo "$cloud: missing, skipped"; continue; }
  out="$OUT/real"
  mkdir -p "$out"
  read -r seconds peak cpu < <(timed_reconstruct "$DATA/$cloud" "$out")
  python3 - "$out/$(stem_of "$cloud")_summary.json" "$cloud" "$seconds" "$peak" "$cpu" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
flags = " ".join(s["quality"]["flags"]) or "-"
print(f"{sys.argv[2]:<26} {s['points']['input']:9d} {float(sys.argv[3]):9.2f} {float(sys.argv[5]):9.2f} {float(sys.argv[4]):8.1f}  {flags}")
PY
done

echo
echo "== 3. scaling on synthetic branching trees (bark points of a trunk and 40 branches) =="
printf "%10s %9s %9s %8s %10s %9s\n" points seconds cpu_s peak_MB internodes branches
for n in $SIZES; do
  cloud="$OUT/synthetic_$n.xyz"
  [[ -f "$cloud" ]] || python3 - "$n" "$cloud" <<'PY'
import math, random, sys
n, path = int(sys.argv[1]), sys.argv[2]
rng = random.Random(4)
# Trunk 12 m (radius 0.25 -> 0.08 m) with 40 laterals (2-5 m, radius 0.02-0.08 m), fixed seed.
segments = [((0.0, 0.0, 0.0), (0.0, 0.0, 12.0), 0.25, 0.08)]
for i in range(40):
    z = 2.0 + 9.5 * i / 40
    r_parent = 0.25 + (0.08 - 0.25) * z / 12
    azimuth, elevation, length = 2.39996 * i, rng.uniform(0.2, 0.8), rng.uniform(2.0, 5.0)
    d = (math.cos(azimuth) * math.cos(elevation), math.sin(azimuth) * math.cos(elevation), math.sin(elevation))
    start = (d[0] * r_parent, d[1] * r_parent, z)
    end = tuple(start[k] + length * d[k] for k in range(3))
    segments.append((start, end, min(0.08, 0.6 * r_parent), 0.01))
areas = [2 * math.pi * 0.5 * (r0 + r1) * math.dist(a, b) for a, b, r0, r1 in segments]
total = sum(areas)
with open(path, "w") as f:
    for (a, b, r0, r1), area in zip(segments, areas):
        axis = [b[k] - a[k] for k in range(3)]
        length = math.sqrt(sum(v * v for v in axis))
        t = [v / length for v in axis]
        u = [1.0, 0.0, 0.0] if abs(t[0]) < 0.9 else [0.0, 1.0, 0.0]
        dot = sum(u[k] * t[k] for k in range(3))
        u = [u[k] - dot * t[k] for k in range(3)]
        norm = math.sqrt(sum(v * v for v in u))
        u = [v / norm for v in u]
        v = [t[1] * u[2] - t[2] * u[1], t[2] * u[0] - t[0] * u[2], t[0] * u[1] - t[1] * u[0]]
        lines = []
        for _ in range(round(n * area / total)):
            s, phi = rng.random(), rng.uniform(-math.pi, math.pi)
            r = r0 + (r1 - r0) * s
            c, si = math.cos(phi), math.sin(phi)
            lines.append("%.4f %.4f %.4f" % tuple(a[k] + s * axis[k] + r * (c * u[k] + si * v[k]) + rng.gauss(0, 0.002) for k in range(3)))
        f.write("\n".join(lines) + "\n")
PY
  out="$OUT/scaling"
  mkdir -p "$out"
  read -r seconds peak cpu < <(timed_reconstruct "$cloud" "$out")
  python3 - "$out/synthetic_${n}_summary.json" "$seconds" "$peak" "$cpu" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"{s['points']['input']:10d} {float(sys.argv[2]):9.2f} {float(sys.argv[4]):9.2f} {float(sys.argv[3]):8.1f} {s['tree']['internodes']:10d} {s['tree']['branches']:9d}")
PY
done

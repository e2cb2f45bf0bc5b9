#!/usr/bin/env bash
# The online refinement's matrix: per cell, `mmlio run` (HVI with loop closure) from the true
# calibration (T) and from the truth with the Velodyne moved by 20 ms, 1 deg about (0.3, 0.5, 0.8)
# and 2 cm along (0.6, -0.5, 0.62) (P); prints ATE P / T and where the passes left the calibration,
# then the median and worst ratio. Every cell's JSON line in OUT/refine.jsonl.
# Usage: scripts/refine_matrix.sh [OUT]   (default refine_out)
#   CELLS="office:1 office:2 office+rm:3 office+rm+rosette:5 lab:1 lab+rm:3 corridor:1 corridor+rm:2
#          office+handheld:1 office+handheld+rm:4 stairs:1 stairs+rm:3"  JOBS=2 MMLIO=build/mmlio
#   CONFIG=config/hvi.yaml   scripts/refine_matrix.sh --summarise OUT prints the table again.
set -euo pipefail
cd "$(dirname "$0")/.."
MMLIO="${MMLIO:-build/mmlio}"

# One cell: simulate, write P, run both, append a JSON line.
cell() {
  local out=$1 spec=$2 scene=${2%%[+:]*} seed=${2##*:} args=()
  [[ $spec == *+handheld* ]] && args+=(--handheld)
  [[ $spec == *+rm* ]] && args+=(--random-mount)
  [[ $spec == *+rosette* ]] && args+=(--pattern rosette)
  local dir="$out/cells/${spec//[:+]/_}"
  mkdir -p "$dir"
  "$MMLIO" -q simulate --scenario "$scene" --seed "$seed" "${args[@]}" --out "$dir/sim" > "$dir/simulate.log" 2>&1
  python3 - "$dir/sim/${scene}_truth.yaml" "$dir/P.yaml" << 'PY'
import math, re, sys
text = open(sys.argv[1]).read()
m = re.search(r"velodyne:\n  T_imu_sensor: \[([^\]]*)\]\n  time_offset_s: ([-0-9.e]+)", text)
v = [float(a) for a in m.group(1).replace("\n", " ").split(",")]
axis = [a / math.sqrt(0.98) for a in (0.3, 0.5, 0.8)]
c, s, (x, y, z) = math.cos(math.radians(1)), math.sin(math.radians(1)), axis
Rd = [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
      [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
      [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]]
d = [0.02 * a / math.sqrt(0.9944) for a in (0.6, -0.5, 0.62)]
R0 = [v[0:3], v[4:7], v[8:11]]
R = [[sum(Rd[i][k] * R0[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
t = [v[3] + d[0], v[7] + d[1], v[11] + d[2]]
T = ", ".join(repr(a) for a in R[0] + [t[0]] + R[1] + [t[1]] + R[2] + [t[2]] + [0, 0, 0, 1])
moved = f"velodyne:\n  T_imu_sensor: [{T}]\n  time_offset_s: {float(m.group(2)) + 0.02!r}"
open(sys.argv[2], "w").write(text[:m.start()] + moved + text[m.end():])
PY
  local which
  for which in T P; do
    local calib="$dir/sim/${scene}_truth.yaml"
    [ "$which" = P ] && calib="$dir/P.yaml"
    "$MMLIO" -q run "$dir/sim/$scene.bag" --config "${CONFIG:-config/hvi.yaml}" --calib "$calib" \
      --gt "$dir/sim/${scene}_gt.tum" --out "$dir/$which" --no-progress > "$dir/$which.log" 2>&1 || true
  done
  rm -f "$dir/sim/$scene.bag"
  python3 - "$dir" "$spec" "$scene" >> "$out/refine.jsonl" << 'PY'
import json, math, re, sys
d, spec, scene = sys.argv[1:]
text = open(f"{d}/sim/{scene}_truth.yaml").read()
m = re.search(r"velodyne:\n  T_imu_sensor: \[([^\]]*)\]\n  time_offset_s: ([-0-9.e]+)", text)
v, offset = [float(a) for a in m.group(1).replace("\n", " ").split(",")], float(m.group(2))
row = {"cell": spec}
for which in ("T", "P"):
    try:
        r = json.load(open(f"{d}/{which}/report.json"))
        row[which] = 100 * r["evaluation"]["ate_rmse_m"]
    except (FileNotFoundError, KeyError):
        row[which] = None
        continue
    if which == "P" and "velodyne" in r.get("online_calibration", {}):
        c = r["online_calibration"]["velodyne"]
        e = c["T_imu_sensor"]
        row["clock_ms"] = 1e3 * (c["time_offset_s"] - offset)
        row["xyz_mm"] = [1e3 * (e[i] - v[i]) for i in (3, 7, 11)]
        tr = sum(v[4 * i + k] * e[4 * i + k] for i in range(3) for k in range(3))
        row["rotation_deg"] = math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))
        row["calibration"] = r["run"]["calibration"]
print(json.dumps(row))
PY
}

summarise() {
  python3 - "$1/refine.jsonl" << 'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
print("| cell | T (cm) | P (cm) | P / T | clock (ms) | x y z (mm) | rotation (deg) |")
print("|---|---|---|---|---|---|---|")
ratios = []
for r in rows:
    if r.get("T") is None or r.get("P") is None:
        print(f"| {r['cell']} | {r.get('T')} | {r.get('P')} | failed | | | |")
        continue
    ratios.append(r["P"] / r["T"])
    xyz = " ".join(f"{a:+.1f}" for a in r.get("xyz_mm", []))
    print(f"| {r['cell']} | {r['T']:.2f} | {r['P']:.2f} | {ratios[-1]:.2f} | {r.get('clock_ms', 0):+.2f} | {xyz} |"
          f" {r.get('rotation_deg', 0):.3f} |")
if ratios:
    print(f"\nP / T median {statistics.median(ratios):.2f}, worst {max(ratios):.2f}, "
          f"within 1.3x {sum(x <= 1.3 for x in ratios)} of {len(ratios)}")
PY
}

if [ "${1:-}" = "--cell" ]; then cell "$2" "$3"; exit 0; fi
if [ "${1:-}" = "--summarise" ]; then summarise "$2"; exit 0; fi
OUT="${1:-refine_out}"
mkdir -p "$OUT"
: > "$OUT/refine.jsonl"
for c in ${CELLS:-office:1 office:2 office+rm:3 office+rm+rosette:5 lab:1 lab+rm:3 corridor:1 corridor+rm:2 \
  office+handheld:1 office+handheld+rm:4 stairs:1 stairs+rm:3}; do
  echo "$0 --cell $OUT $c"
done | parallel --will-cite -j "${JOBS:-2}"
summarise "$OUT"

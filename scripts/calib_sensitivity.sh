#!/usr/bin/env bash
# How far a hair of calibration moves a run: simulates SCENE with SEED as scripts/accuracy_job.sh does
# (IMU noise level 1), then runs HVI without loop closure from the true calibration and from it moved
# by 1 mm along x, -x, y and z, by 0.02 deg of yaw either way and by 0.3 ms of clock (far inside what
# `mmlio calibrate` states), and prints each run's ATE. A scene whose ATE moves more than the 1.2x a
# self-calibrated run is judged by cannot judge a calibration; a big spread points at the odometry.
# Usage: scripts/calib_sensitivity.sh SCENE SEED [OUT]   (SCENE+handheld: carried by hand; MMLIO=build/mmlio)
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/matrix_cell.sh
source scripts/matrix_cell.sh
scene=$1 seed=$2 out=${3:-sensitivity_out}
base=${scene%+handheld}
dir="$out/$scene-s$seed"
export MMLIO="${MMLIO:-build/mmlio}" dir base
[ -f "$dir/$base.bag" ] || simulate_cell "$MMLIO" "$scene" "$seed" 1 0 "$dir"
one() {
  local tag=$1 dx=$2 dy=$3 dz=$4 yaw=$5 dt=$6
  python3 - "$dir/${base}_truth.yaml" "$dir/calib_$tag.yaml" "$dx" "$dy" "$dz" "$yaw" "$dt" << 'PY'
import math, re, sys
src, out = sys.argv[1], sys.argv[2]
dx, dy, dz, yaw, dt = (float(v) for v in sys.argv[3:8])
text = open(src).read()
i = text.index("velodyne:")
seg = text[i:]
m = re.search(r"T_imu_sensor: \[([^\]]*)\]", seg)
v = [float(x) for x in m.group(1).replace("\n", " ").split(",")]
c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
Rz = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
R = [v[0:3], v[4:7], v[8:11]]
R2 = [[sum(Rz[a][k] * R[k][b] for k in range(3)) for b in range(3)] for a in range(3)]
t = [v[3] + dx / 1e3, v[7] + dy / 1e3, v[11] + dz / 1e3]
rows = [R2[r] + [t[r]] for r in range(3)] + [[0, 0, 0, 1]]
seg = seg[:m.start()] + "T_imu_sensor: [" + ", ".join(repr(x) for row in rows for x in row) + "]" + seg[m.end():]
o = re.search(r"time_offset_s: ([-0-9.e]+)", seg)
seg = seg[:o.start()] + "time_offset_s: " + repr(float(o.group(1)) + dt / 1e3) + seg[o.end():]
open(out, "w").write(text[:i] + seg)
PY
  "$MMLIO" -q run "$dir/$base.bag" --config config/hvi.yaml --calib "$dir/calib_$tag.yaml" --no-loop --no-progress \
    --out "$dir/run_$tag" > "$dir/run_$tag.log" 2>&1 || true
  local ate
  ate=$("$MMLIO" evaluate --gt "$dir/${base}_gt.tum" --est "$dir/run_$tag/trajectory.tum" --json |
    python3 -c 'import json, sys; print("%.3f" % (100 * json.load(sys.stdin)["ate_rmse_m"]))')
  echo "$tag $ate"
}
export -f one
printf '%s\n' "truth 0 0 0 0 0" "x+1mm 1 0 0 0 0" "x-1mm -1 0 0 0 0" "y+1mm 0 1 0 0 0" "z+1mm 0 0 1 0 0" \
  "yaw+0.02deg 0 0 0 0.02 0" "yaw-0.02deg 0 0 0 -0.02 0" "clock+0.3ms 0 0 0 0 0.3" |
  parallel --will-cite -k -j "${JOBS:-2}" --colsep ' ' one '{1}' '{2}' '{3}' '{4}' '{5}' '{6}' | tee "$dir/ate_cm.txt"
python3 - "$dir/ate_cm.txt" << 'PY'
import sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
truth = float(rows[0][1]); rest = [float(r[1]) for r in rows[1:]]
print(f"truth {truth:.3f} cm; perturbed {min(rest):.3f}-{max(rest):.3f} cm; worst {max(rest) / truth:.2f}x the truth")
PY

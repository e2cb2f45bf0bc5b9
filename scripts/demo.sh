#!/usr/bin/env bash
# The demo: installs, builds, simulates the `office` sequence (with a 70 ms Velodyne clock offset),
# describes the bag, calibrates the Velodyne against the Livox, runs HVI odometry and mapping with
# that calibration and scores the trajectory against the simulator's ground truth.
# Usage: scripts/demo.sh [OUT_DIR] (default: demo_out)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-demo_out}"
scripts/build.sh --target mmlio
MMLIO=build/mmlio

echo "== simulate the office sequence (VLP-16 + Livox Horizon + IMU) =="
"$MMLIO" simulate --scenario office --time-offset 0.07 --out "$OUT"
echo "== what is in the bag =="
"$MMLIO" info "$OUT/office.bag"
echo "== LiDAR-to-LiDAR calibration (truth: $OUT/office_truth.yaml) =="
"$MMLIO" calibrate "$OUT/office.bag" --config config/hvi.yaml --out "$OUT/calib.yaml"
echo "== HVI odometry and mapping =="
"$MMLIO" run "$OUT/office.bag" --config config/hvi.yaml --calib "$OUT/calib.yaml" \
  --gt "$OUT/office_gt.tum" --out "$OUT/run"
echo "== accuracy against ground truth =="
"$MMLIO" evaluate --gt "$OUT/office_gt.tum" --est "$OUT/run/trajectory.tum" --plot "$OUT/run/evaluation.png"
echo "outputs: $OUT/calib.yaml, $OUT/run/{trajectory.tum,map.pcd,report.json,report.md,map_top.png,evaluation.png}"

#!/usr/bin/env bash
# The demo: installs, builds, simulates the `office` sequence (with a 70 ms Velodyne clock offset),
# and then does what a user does with a bag of their own rig: describes the bag, writes a starter
# rig config from it, calibrates the Velodyne against the Livox, runs HVI odometry and mapping
# with that calibration and scores the trajectory against the simulator's ground truth.
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
echo "== a starter rig config from the bag =="
"$MMLIO" init "$OUT/office.bag" --out "$OUT/rig.yaml" --force
echo "== LiDAR-to-LiDAR calibration (truth: $OUT/office_truth.yaml) =="
"$MMLIO" calibrate "$OUT/office.bag" --config "$OUT/rig.yaml" --out "$OUT/calib.yaml"
echo "== HVI odometry and mapping =="
"$MMLIO" run "$OUT/office.bag" --config "$OUT/rig.yaml" --calib "$OUT/calib.yaml" \
  --gt "$OUT/office_gt.tum" --out "$OUT/run"
echo "== accuracy against ground truth =="
"$MMLIO" evaluate --gt "$OUT/office_gt.tum" --est "$OUT/run/trajectory.tum" --plot "$OUT/run/evaluation.svg"
echo "outputs: $OUT/rig.yaml, $OUT/calib.yaml, $OUT/run/{trajectory.tum,map.pcd,report.html,report.json,report.md,config_used.yaml,evaluation.svg}"
echo "open $OUT/run/report.html in a browser: the map in 3D, the plots, every figure of the run"

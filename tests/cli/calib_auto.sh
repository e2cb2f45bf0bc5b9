#!/usr/bin/env bash
# CTest: `mmlio run --calib auto` calibrates as `mmlio calibrate` does: the same calib.yaml, byte for
# byte, so what the accuracy matrix measures for calibrate-then-run holds for --calib auto.
# Usage: calib_auto.sh MMLIO_BINARY
set -euo pipefail
mmlio="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# A start still for a second, then walking and turning, the spinning LiDAR 30 ms late.
"$mmlio" -q simulate --scenario office --duration 16 --time-offset 0.03 --out "$work/sim" > /dev/null
"$mmlio" init "$work/sim/office.bag" --out "$work/rig.yaml" > /dev/null
"$mmlio" calibrate "$work/sim/office.bag" --config "$work/rig.yaml" --out "$work/calib.yaml" > "$work/calibrate.log"
"$mmlio" -q run "$work/sim/office.bag" --config "$work/rig.yaml" --calib auto --no-loop --no-progress \
  --out "$work/run" > "$work/run.log" 2>&1 || { echo "FAIL: run --calib auto: $(tail -3 "$work/run.log")"; exit 1; }
if ! cmp -s "$work/calib.yaml" "$work/run/calib.yaml"; then
  echo "FAIL: run --calib auto wrote another calibration than mmlio calibrate:"
  diff "$work/calib.yaml" "$work/run/calib.yaml" | head -20
  exit 1
fi
grep -q '"calibration": "auto (' "$work/run/report.json" || { echo "FAIL: report.json does not record the auto calibration"; exit 1; }
grep -q "clock offset .* ms" "$work/calibrate.log" || { echo "FAIL: the clock offset was not estimated: $(cat "$work/calibrate.log")"; exit 1; }
echo "PASS: run --calib auto and calibrate agree byte for byte ($(grep -c . "$work/calib.yaml") lines)"

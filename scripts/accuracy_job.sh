#!/usr/bin/env bash
# One cell of the accuracy matrix: simulates SCENE with SEED at IMU noise LEVEL (1, 3, 5: multiples
# of a Livox-Horizon-like BMI088 IMU), runs every MODE on it with the true calibration, scores
# trajectory and map, prints one JSON line per run and deletes the bag (KEEP_BAGS=1 keeps it).
# The cell's pattern, mount and IMU follow its seed and level (scripts/matrix_cell.sh).
# PEOPLE=N (default 0) puts N people walking through the scene (simulate --people N); the map is then
# also scored for what is off the static surfaces. KEEP_MAPS=1 keeps each run's maps (accuracy.sh
# compares the maps of a cell with people against the same cell without).
# SCENE+handheld carries the scene's route by hand (simulate --handheld).
# A mode ending in +user is the user's run instead: `mmlio calibrate` on the bag with the preset (its
# placeholder mount as the starting guess), then the run with that calibration, as the README says;
# the row also gets the calibration's errors against the truth.
# Usage: scripts/accuracy_job.sh OUT SCENE SEED LEVEL [MODES...]   (modes: hvi vi hi hvi+loop hvi+user ...)
set -euo pipefail
# shellcheck source=scripts/matrix_cell.sh
source "$(dirname "$0")/matrix_cell.sh"
OUT="$1" SCENE="$2" SEED="$3" LEVEL="$4"
shift 4
CELL_SCENE="$SCENE"
SCENE="${SCENE%+handheld}"
MODES=("${@:-hvi vi hi}")
read -r -a MODES <<< "${MODES[*]}"
MMLIO="${MMLIO:-build/mmlio}"
CONFIG_DIR="${CONFIG_DIR:-config}"
PEOPLE="${PEOPLE:-0}"
cell="$CELL_SCENE-s$SEED-n$LEVEL"
[ "$PEOPLE" -gt 0 ] && cell="$cell-p$PEOPLE"
dir="$OUT/$cell"
pattern=$(cell_pattern "$SEED")
simulate_cell "$MMLIO" "$CELL_SCENE" "$SEED" "$LEVEL" "$PEOPLE" "$dir"

for run in "${MODES[@]}"; do
  base_run="${run%+user}"
  mode="${base_run%+loop}"
  loop_flag="--no-loop"
  [ "$base_run" = "hvi+loop" ] && loop_flag=""
  rd="$dir/$run"
  status=ok
  code=0
  calib="$dir/${SCENE}_truth.yaml"
  if [ "$base_run" != "$run" ]; then
    # The user's rig file: the preset with the solid-state LiDAR's factory extrinsic (the truth's;
    # a random mount draws it too), the spinning LiDAR on the preset's placeholder mount.
    python3 - "$CONFIG_DIR/$mode.yaml" "$dir/${SCENE}_truth.yaml" "$dir/user_rig_$mode.yaml" <<'PY'
import re, sys
preset, truth, out = sys.argv[1:]
matrix = re.search(r"livox:\s*\n\s*T_imu_sensor: (\[[^\]]*\])", open(truth).read()).group(1)
text = open(preset).read()
name = text.index("name: livox")
m = re.compile(r"T_imu_sensor: \[[^\]]*\]").search(text, name)
open(out, "w").write(text[:m.start()] + "T_imu_sensor: " + " ".join(matrix.split()) + text[m.end():])
PY
    calib="$dir/user_calib.yaml"
    [ -f "$calib" ] || "$MMLIO" calibrate "$dir/$SCENE.bag" --config "$dir/user_rig_$mode.yaml" --out "$calib" \
      > "$dir/calibrate.log" 2>&1 || code=$?
  fi
  [ "$code" -eq 0 ] && "$MMLIO" -q run "$dir/$SCENE.bag" --config "$CONFIG_DIR/$mode.yaml" --calib "$calib" $loop_flag \
    --no-progress --out "$rd" > "$rd.log" 2>&1 || code=$?
  [ "$code" -eq 3 ] && status=untrusted  # outputs written, the run says why they are not to be trusted
  [ "$code" -ne 0 ] && [ "$code" -ne 3 ] && status=failed
  ev='{}'
  if [ "$status" != failed ]; then
    removed=()
    [ -f "$rd/map_dynamic.pcd" ] && removed=(--removed "$rd/map_dynamic.pcd")
    ev=$("$MMLIO" evaluate --gt "$dir/${SCENE}_gt.tum" --est "$rd/trajectory.tum" --map "$rd/map.pcd" \
      "${removed[@]}" --scenario "$SCENE" --json 2>/dev/null || echo '{}')
  fi
  python3 - "$CELL_SCENE" "$SEED" "$LEVEL" "$pattern" "$run" "$status" "$rd" "$ev" "$PEOPLE" "$calib" \
    "$dir/${SCENE}_truth.yaml" <<'PY'
import json, math, os, re, sys
scene, seed, level, pattern, run, status, rd, ev, people, calib, truth = sys.argv[1:]
row = {"scene": scene, "seed": int(seed), "noise": int(level), "pattern": pattern, "people": int(people), "run": run,
       "status": status}
row.update(json.loads(ev))
def velodyne(path):
    text = open(path).read()
    m = re.search(r"velodyne:\s*\n\s*T_imu_sensor: \[([^\]]*)\]", text)
    t = re.search(r"velodyne:[\s\S]*?time_offset_s: ([-0-9.e]+)", text)
    v = [float(x) for x in m.group(1).replace("\n", " ").split(",")]
    return [v[0:4], v[4:8], v[8:12]], float(t.group(1))
def calibration_errors(est_path, prefix):
    (Te, te), (Tt, tt) = velodyne(est_path), velodyne(truth)
    row[prefix + "clock_err_ms"] = 1000 * (te - tt)
    row[prefix + "extrinsic_err_mm"] = 1000 * math.dist([r[3] for r in Te], [r[3] for r in Tt])
    tr = sum(Te[i][j] * Tt[i][j] for i in range(3) for j in range(3))
    row[prefix + "extrinsic_err_deg"] = math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))
if run.endswith("+user") and os.path.exists(calib):
    calibration_errors(calib, "calib_")
refined = os.path.join(rd, "calibration_refined.yaml")
if os.path.exists(refined):
    calibration_errors(refined, "refined_")
rep = os.path.join(rd, "report.json")
if os.path.exists(rep):
    r = json.load(open(rep))
    t = r.get("timing", {})
    row["odometry_ms"] = sum(v["mean_ms"] for k, v in t.items() if k not in ("total", "mapping_backend"))
    row["degenerate_sweeps"] = r.get("sweeps", {}).get("degenerate", None)
    row["map_points_removed"] = r.get("dynamic", {}).get("map_points_removed", None)
print(json.dumps(row))
PY
  [ "${KEEP_MAPS:-0}" = 1 ] || rm -rf "$rd/map.pcd" "$rd"/map_*.pcd
done
[ "${KEEP_BAGS:-0}" = 1 ] || rm -f "$dir/$SCENE.bag"

#!/usr/bin/env bash
# Accuracy table of the README: simulates office, corridor and hall (default seeds), runs
# HVI / VI / HI odometry without loop closure and HVI with it, and prints one markdown row per
# run from `mmlio evaluate --json`.
# Usage: scripts/accuracy.sh [OUT_DIR] [SCENARIOS...]   (default: accuracy_out office corridor hall)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-accuracy_out}"
shift || true
SCENARIOS=("${@:-office corridor hall}")
read -r -a SCENARIOS <<< "${SCENARIOS[*]}"
MMLIO="${MMLIO:-build/mmlio}"
[ -x "$MMLIO" ] || scripts/build.sh --target mmlio

echo "| scenario | path m | run | ATE RMSE m | RPE 10 m % | end-to-end m | end-to-end % of path | ms/sweep (odometry) |"
echo "|---|---|---|---|---|---|---|---|"
for sc in "${SCENARIOS[@]}"; do
  [ -f "$OUT/$sc.bag" ] || "$MMLIO" -q simulate --scenario "$sc" --out "$OUT" >/dev/null
  for run in hvi vi hi hvi+loop; do
    mode="${run%+loop}"
    loop_flag="--no-loop"
    [ "$run" = "hvi+loop" ] && loop_flag=""
    dir="$OUT/$sc-$run"
    if ! "$MMLIO" -q run "$OUT/$sc.bag" --config "config/$mode.yaml" --calib "$OUT/${sc}_truth.yaml" \
        $loop_flag --no-progress --out "$dir" > "$dir.log" 2>&1; then
      echo "| $sc | | $run | failed: $(tail -n 1 "$dir.log") | | | | |"
      continue
    fi
    python3 - "$sc" "$run" "$dir" "$OUT/${sc}_gt.tum" "$MMLIO" <<'PY'
import json, subprocess, sys
sc, run, d, gt, mmlio = sys.argv[1:]
ev = json.loads(subprocess.check_output([mmlio, "evaluate", "--gt", gt, "--est", d + "/trajectory.tum", "--json"]))
rep = json.load(open(d + "/report.json"))
t = rep["timing"]
odo = sum(t[s]["mean_ms"] for s in t if s not in ("total", "mapping_backend"))
path = ev.get("path_length_m") or 0
e2e = ev["end_to_end_m"]
print(f"| {sc} | {path:.1f} | {run} | {ev['ate_rmse_m']:.4f} | {ev['rpe_10m_pct']:.3f} | {e2e:.3f} | "
      f"{100 * e2e / path if path else float('nan'):.3f} | {odo:.1f} |")
PY
  done
done

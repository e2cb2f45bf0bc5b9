#!/usr/bin/env bash
# Two builds of mmlio side by side on the same simulated bags, for an estimator change: each cell is
# simulated once (kept in OUT/bags, so the next comparison starts at once), both binaries run it
# with the true calibration and no loop closure in each mode, and the table gives per cell the ATE
# and the height error against gravity (what the alignment hides) of A and B, then B / A as median
# and worst. Every run's JSON line in OUT/ab.jsonl; only trajectories and reports are kept.
# Usage: scripts/ab_matrix.sh BIN_A BIN_B [OUT]   (default ab_out)
#   CELLS="office:1 office:2 office:3 hall:1 ..." (scene[+handheld]:seed, simulated by the matrix's
#   rules at IMU noise level 1, scripts/matrix_cell.sh; default: seeds 1-3 of the seven scenes)
#   MODES="hvi vi"   JOBS=2   CONFIG_DIR=config
#   scripts/ab_matrix.sh --summarise OUT prints the table again.
set -euo pipefail
cd "$(dirname "$0")/.."

summarise() {
  python3 - "$1/ab.jsonl" << 'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
runs = {(r["cell"], r["mode"], r["which"]): r for r in rows}
def cm(r, key):
    return f'{100 * r[key]:.2f}' if r and r.get(key) is not None else "n/a"
for mode in sorted({r["mode"] for r in rows}):
    print(f"\n{mode}: ATE cm A / B, height error against gravity cm A / B")
    print("| cell | ATE A | ATE B | B / A | height A | height B |")
    print("|---|---|---|---|---|---|")
    ratios, heights = [], []
    for cell in sorted({r["cell"] for r in rows if r["mode"] == mode}):
        a, b = runs.get((cell, mode, "A")), runs.get((cell, mode, "B"))
        ratio = "n/a"
        if a and b and a.get("ate_rmse_m") and b.get("ate_rmse_m") is not None:
            ratios.append(b["ate_rmse_m"] / a["ate_rmse_m"])
            ratio = f"{ratios[-1]:.2f}"
        if a and b and a.get("height_error_max_m") is not None and b.get("height_error_max_m") is not None:
            heights.append((a["height_error_max_m"], b["height_error_max_m"]))
        print(f"| {cell} | {cm(a, 'ate_rmse_m')} | {cm(b, 'ate_rmse_m')} | {ratio} | "
              f"{cm(a, 'height_error_max_m')} | {cm(b, 'height_error_max_m')} |")
    if ratios:
        print(f"B / A: median {statistics.median(ratios):.2f}, best {min(ratios):.2f}, worst {max(ratios):.2f}"
              f" over {len(ratios)} cells")
    if heights:
        print("height error median A {:.1f} / B {:.1f} cm, worst A {:.1f} / B {:.1f} cm".format(
            100 * statistics.median(h[0] for h in heights), 100 * statistics.median(h[1] for h in heights),
            100 * max(h[0] for h in heights), 100 * max(h[1] for h in heights)))
PY
}
if [ "${1:-}" = "--summarise" ]; then summarise "$2"; exit 0; fi
[ $# -ge 2 ] || { echo "usage: scripts/ab_matrix.sh BIN_A BIN_B [OUT]" >&2; exit 1; }
A=$(realpath "$1") B=$(realpath "$2") OUT="${3:-ab_out}"
mkdir -p "$OUT/bags"
: > "$OUT/ab.jsonl"
default_cells=""
for scene in office office+handheld corridor hall stairs ramp lab; do
  for seed in 1 2 3; do default_cells+="$scene:$seed "; done
done

# One cell: simulate unless kept, then every mode with both binaries; a JSON line per run.
cell() {
  # shellcheck source=scripts/matrix_cell.sh
  source scripts/matrix_cell.sh
  local out=$1 spec=$2 scene=${2%%[+:]*} seed=${2##*:}
  local bag="$out/bags/${spec//[:+]/_}"
  [ -f "$bag/$scene.bag" ] || simulate_cell "$A" "${spec%%:*}" "$seed" 1 0 "$bag" || true
  local mode which bin rd
  for mode in ${MODES:-hvi vi}; do
    for which in A B; do
      bin=$A
      [ "$which" = B ] && bin=$B
      rd="$out/runs/${spec//[:+]/_}/$mode-$which"
      mkdir -p "$(dirname "$rd")"
      "$bin" -q run "$bag/$scene.bag" --config "${CONFIG_DIR:-config}/$mode.yaml" --calib "$bag/${scene}_truth.yaml" \
        --no-loop --no-progress --out "$rd" > "$rd.log" 2>&1 || true
      rm -rf "$rd/session" "$rd"/map*.pcd "$rd/report.html"  # a hall run leaves 140 MB otherwise
      local ev='{}'
      [ -f "$rd/trajectory.tum" ] &&
        ev=$("$A" evaluate --gt "$bag/${scene}_gt.tum" --est "$rd/trajectory.tum" --json 2>/dev/null || echo '{}')
      python3 -c 'import json, sys; r = json.loads(sys.argv[4]); r.update(cell=sys.argv[1], mode=sys.argv[2], which=sys.argv[3]); print(json.dumps(r))' \
        "$spec" "$mode" "$which" "$ev" >> "$out/ab.jsonl"
    done
  done
}
export -f cell
export A B MODES CONFIG_DIR
for spec in ${CELLS:-$default_cells}; do echo "$spec"; done |
  parallel --will-cite -j "${JOBS:-2}" cell "$OUT" {}
summarise "$OUT"

#!/usr/bin/env bash
# The calibration matrix: what `mmlio calibrate` gives a user over scenes, seeds, Velodyne clock
# offsets of either sign and sweep phases between the LiDARs, several cells at a time through GNU
# parallel. Prints per scene the clock offset's error (median, worst), how often it lies within 3
# stated sigmas, the refusals, and the extrinsic's error (and how often every axis of it lies
# within 3 stated sigmas); every cell's JSON line in OUT/calib.jsonl.
# Usage: scripts/calib_matrix.sh [OUT]   (default calib_out)
#   SCENES="office corridor hall lab office+handheld stairs" SEEDS="1 2" OFFSETS="-30 0 25" PHASES="0 37 73"
#   DURATION=0 (the full walk; shorter walks part of the route out and back) JOBS=2 MMLIO=build/mmlio
#   scripts/calib_matrix.sh --summarise OUT prints the table of an existing calib.jsonl.
set -euo pipefail
cd "$(dirname "$0")/.."
summarise() {
  python3 - "$1/calib.jsonl" << 'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
print("| scene | cells | offset error median / worst (ms) | within 3 sigma | refused | extrinsic median / worst (mm) | (deg) | within 3 sigmas |")
print("|---|---|---|---|---|---|---|---|")
for scene in sorted({r["scene"] for r in rows}):
    rs = [r for r in rows if r["scene"] == scene]
    est = [r for r in rs if r["offset_estimated"]]
    err = [abs(r["offset_err_ms"]) for r in est]
    cov = sum(abs(r["offset_err_ms"]) <= 3 * r["sigma_ms"] for r in est)
    ext = [r["extrinsic_err_mm"] for r in rs if r.get("extrinsic_err_mm") is not None]
    deg = [r["extrinsic_err_deg"] for r in rs if r.get("extrinsic_err_deg") is not None]
    zs = [r["extrinsic_max_sigmas"] for r in rs if r.get("extrinsic_max_sigmas") is not None]
    f = lambda v: f"{statistics.median(v):.1f} / {max(v):.1f}" if v else "n/a"
    g = lambda v: f"{statistics.median(v):.3f} / {max(v):.3f}" if v else "n/a"
    print(f"| {scene} | {len(rs)} | {f(err)} | {cov}/{len(est)} | {len(rs) - len(est)} | {f(ext)} | {g(deg)} | {sum(z <= 3 for z in zs)}/{len(zs)} |")
PY
}
if [ "${1:-}" = "--summarise" ]; then summarise "$2"; exit 0; fi
OUT="${1:-calib_out}"
mkdir -p "$OUT"
: > "$OUT/calib.jsonl"
for sc in ${SCENES:-office corridor hall lab office+handheld stairs}; do for seed in ${SEEDS:-1 2}; do
  for o in ${OFFSETS:--30 0 25}; do for p in ${PHASES:-0 37 73}; do
    echo "scripts/calib_job.sh $OUT $sc $seed $o $p"
  done; done
done; done | parallel --will-cite -j "${JOBS:-2}"
summarise "$OUT"

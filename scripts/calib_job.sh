#!/usr/bin/env bash
# One cell of scripts/calib_matrix.sh: simulates SCENE (SEED, the Velodyne's clock OFFSET_MS and its
# sweep PHASE_MS after the Livox's frames), runs `mmlio calibrate` as the README tells a user (the
# presets' mount as the starting guess), and appends the estimate against the truth as one JSON line
# to OUT/calib.jsonl. The bag is removed afterwards.
# Usage: scripts/calib_job.sh OUT SCENE SEED OFFSET_MS PHASE_MS   (SCENE+handheld: carried by hand)
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1 scene=$2 seed=$3 offset_ms=$4 phase_ms=$5
base=${scene%+handheld}
extra=()
[ "$base" != "$scene" ] && extra+=(--handheld)
cell="$out/cells/${scene}_s${seed}_o${offset_ms}_p${phase_ms}"
mkdir -p "$cell"
"${MMLIO:-build/mmlio}" -q simulate --scenario "$base" --seed "$seed" --duration "${DURATION:-0}" "${extra[@]}" \
  --time-offset "$(python3 -c "print($offset_ms / 1000)")" --velodyne-phase "$(python3 -c "print($phase_ms / 1000)")" \
  ${SIM_ARGS:-} --out "$cell/sim" > "$cell/simulate.log" 2>&1
start=$(date +%s.%N)
"${MMLIO:-build/mmlio}" calibrate "$cell/sim/$base.bag" --config config/hvi.yaml --out "$cell/calib.yaml" > "$cell/calibrate.log" 2>&1 || true
end=$(date +%s.%N)
rm -f "$cell/sim/$base.bag"
python3 - "$cell" "$scene" "$seed" "$offset_ms" "$phase_ms" "$start" "$end" >> "$out/calib.jsonl" << 'PY'
import json, math, re, sys
cell, scene, seed, offset_ms, phase_ms, start, end = sys.argv[1:]
def matrices(path):
    text = open(path).read()
    out = {}
    for name in ("livox", "velodyne"):
        m = re.search(name + r":\s*\n\s*T_imu_sensor: \[([^\]]*)\]", text)
        t = re.search(name + r":[\s\S]*?time_offset_s: ([-0-9.e]+)", text)
        if m:
            v = [float(x) for x in m.group(1).replace("\n", " ").split(",")]
            out[name] = ([v[0:4], v[4:8], v[8:12]], float(t.group(1)) if t else None)
    return out
truth = matrices(f"{cell}/sim/{scene.split('+')[0]}_truth.yaml")["velodyne"]
row = {"scene": scene, "seed": int(seed), "offset_ms": float(offset_ms), "phase_ms": float(phase_ms),
       "seconds": float(end) - float(start)}
log = open(f"{cell}/calibrate.log").read()
m = re.search(r"clock offset ([-0-9.]+) \+- ([0-9.]+) ms", log)
row["offset_estimated"] = m is not None
if m:
    row["offset_est_ms"], row["sigma_ms"] = float(m.group(1)), float(m.group(2))
    row["offset_err_ms"] = row["offset_est_ms"] - float(offset_ms)
else:
    row["message"] = next((l.strip() for l in log.splitlines() if "clock offset" in l or "refused" in l), log.strip()[-200:])
try:
    est = matrices(f"{cell}/calib.yaml")["velodyne"]
    te = [r[3] for r in est[0]]; tt = [r[3] for r in truth[0]]
    row["extrinsic_err_mm"] = 1000 * math.dist(te, tt)
    Re = [r[:3] for r in est[0]]; Rt = [r[:3] for r in truth[0]]
    tr = sum(Re[i][j] * Rt[i][j] for i in range(3) for j in range(3))
    row["extrinsic_err_deg"] = math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))
    # Per axis against the stated sigmas: translation, and the rotation R_est R_truth^T as a vector.
    text = open(f"{cell}/calib.yaml").read()
    text = text[text.index("velodyne:"):]
    ts = [float(x) for x in re.search(r"translation_sigma_m: \[([^\]]*)\]", text).group(1).split(",")]
    rs = [math.radians(float(x)) for x in re.search(r"rotation_sigma_deg: \[([^\]]*)\]", text).group(1).split(",")]
    D = [[sum(Re[i][k] * Rt[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    ang = math.acos(max(-1.0, min(1.0, (D[0][0] + D[1][1] + D[2][2] - 1) / 2)))
    f = ang / (2 * math.sin(ang)) if ang > 1e-9 else 0.5
    w = [f * (D[2][1] - D[1][2]), f * (D[0][2] - D[2][0]), f * (D[1][0] - D[0][1])]
    z = [abs(te[i] - tt[i]) / ts[i] for i in range(3)] + [abs(w[i]) / rs[i] for i in range(3)]
    row["extrinsic_max_sigmas"] = max(z)
except (FileNotFoundError, KeyError):
    row["extrinsic_err_mm"] = None
print(json.dumps(row))
PY

#!/usr/bin/env bash
# The accuracy matrix of the README: every scene x seed x IMU noise level, each run in every mode
# with the true calibration, several cells at a time through GNU parallel. Prints the median and
# worst ATE, end-to-end error (% of path) and map sharpness per scene and mode, and keeps every
# run's JSON line in OUT/results.jsonl.
# Usage: scripts/accuracy.sh [OUT]   (default accuracy_out)
#   SCENES="office corridor corridor_blind hall stairs ramp lab office+handheld corridor+handheld" SEEDS="1 2 3"
#   NOISE="1 3 5" MODES="hvi vi hi" PEOPLE="0"   (SCENE+handheld: the scene's route carried by hand;
#   MODES="hvi hvi+user": also the user's run, `mmlio calibrate` first, with its own table)
#   (PEOPLE="0 4": every cell also with 4 people walking; the table then has a row per people count)
#   JOBS=2 (parallel cells; each run also uses TBB threads)
#   scripts/accuracy.sh --list prints the job commands instead (one per line, for a cluster scheduler),
#   scripts/accuracy.sh --summarise OUT prints the table of an existing results.jsonl.
set -euo pipefail
cd "$(dirname "$0")/.."
SCENES="${SCENES:-office corridor corridor_blind hall stairs ramp lab office+handheld corridor+handheld}"
SEEDS="${SEEDS:-1 2 3}"
NOISE="${NOISE:-1 3 5}"
MODES="${MODES:-hvi vi hi}"
PEOPLE="${PEOPLE:-0}"
JOBS="${JOBS:-2}"

jobs() {
  for sc in $SCENES; do for seed in $SEEDS; do for n in $NOISE; do for p in $PEOPLE; do
    echo "PEOPLE=$p scripts/accuracy_job.sh $1 $sc $seed $n $MODES"
  done; done; done; done
}

summarise() {
  python3 - "$1/results.jsonl" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
order = {"hvi": 0, "vi": 1, "hi": 2, "hvi+loop": 3, "hvi+user": 4, "hvi+loop+user": 5}
def fmt(v, scale=100, unit="cm", digits=2):
    return "n/a" if v is None else f"{v * scale:.{digits}f}{(' ' + unit) if unit else ''}"
for r in rows:
    if r.get("people", 0):
        r["scene"] = f'{r["scene"]} +{r["people"]} people'
print("| scene | run | runs | ATE median | ATE worst | height against gravity, worst error median / worst | end-to-end % of path median / worst | map to surfaces median | map off surfaces median / worst | HVI <= min(VI, HI) |")
print("|---|---|---|---|---|---|---|---|---|---|")
base = ["office", "corridor", "corridor_blind", "hall", "stairs", "ramp", "lab"]
scenes = sorted({r["scene"] for r in rows}, key=lambda s: (base.index(s.split()[0].split("+")[0]) if s.split()[0].split("+")[0] in base else 9, s))
for sc in scenes:
    cells = {}
    for r in rows:
        if r["scene"] == sc:
            cells.setdefault((r["seed"], r["noise"]), {})[r["run"]] = r
    for run in sorted({r["run"] for r in rows if r["scene"] == sc}, key=lambda m: order.get(m, 9)):
        rs = [r for r in rows if r["scene"] == sc and r["run"] == run]
        ok = [r for r in rs if r["status"] in ("ok", "untrusted") and "ate_rmse_m" in r]
        untrusted = sum(r["status"] == "untrusted" for r in ok)
        ate = [r["ate_rmse_m"] for r in ok]
        # What the alignment hides: a run tilted whole (evaluate: against gravity, not aligned).
        height = [r["height_error_max_m"] for r in ok if "height_error_max_m" in r]
        # How far the end is off, beyond the true end-to-end distance (0 for routes that return).
        e2e = [100 * abs(r["end_to_end_m"] - r.get("gt_end_to_end_m", 0.0)) / r["path_length_m"]
               for r in ok if r.get("path_length_m")]
        mp = [r["map_median_m"] for r in ok if "map_median_m" in r]
        off = [r["map_off_surface_fraction"] for r in ok if "map_off_surface_fraction" in r]
        failed = len(rs) - len(ok)
        beat = ""
        if run == "hvi":
            wins = 0; total = 0
            for c in cells.values():
                if "hvi" in c and "ate_rmse_m" in c["hvi"]:
                    others = [c[m]["ate_rmse_m"] for m in ("vi", "hi") if m in c and "ate_rmse_m" in c[m]]
                    if others:
                        total += 1; wins += c["hvi"]["ate_rmse_m"] <= min(others) * 1.0 + 1e-9
            beat = f"{wins}/{total}"
        notes = ", ".join(n for n in (f"{untrusted} untrusted" if untrusted else "", f"{failed} failed" if failed else "") if n)
        print(f"| {sc} | {run} | {len(ok)}{f' ({notes})' if notes else ''} | "
              f"{fmt(statistics.median(ate)) if ate else 'n/a'} | {fmt(max(ate)) if ate else 'n/a'} | "
              f"{f'{fmt(statistics.median(height), unit=None, digits=1)} / {fmt(max(height), digits=1)}' if height else 'n/a'} | "
              f"{f'{statistics.median(e2e):.3f} / {max(e2e):.3f}' if e2e else 'n/a'} | "
              f"{fmt(statistics.median(mp), 1000, 'mm', 1) if mp else 'n/a'} | "
              f"{f'{100 * statistics.median(off):.2f} / {100 * max(off):.2f} %' if off else 'n/a'} | {beat} |")
# Static surface with people against the same cell without: the share of the empty run's
# static-surface points the people run still has within 10 cm (map_static_kept, added by
# score_static_kept), and the static voxels only the removed points (map_dynamic.pcd) cover.
kept = []
for r in rows:
    if not r.get("people") or "map_static_voxels" not in r:
        continue
    base = [b for b in rows if not b.get("people") and b["seed"] == r["seed"] and b["noise"] == r["noise"]
            and b["run"] == r["run"] and b["scene"] == r["scene"].split()[0] and b.get("map_static_voxels")]
    if base:
        kept.append((r, base[0]["map_static_voxels"]))
if kept:
    print()
    print("| cell | run | static points kept (of the cell without people) | static voxels only the removed points cover |")
    print("|---|---|---|---|")
    for r, empty in kept:
        removed = r.get("map_static_voxels_removed")
        points = r.get("map_static_kept")
        print(f'| {r["scene"]} s{r["seed"]} n{r["noise"]} | {r["run"]} | '
              f'{"n/a" if points is None else f"{100 * points:.1f} %"} | '
              f'{"n/a" if removed is None else f"{100 * removed / empty:.1f} %"} |')
# The user's runs (MODES with +user): `mmlio calibrate`'s errors, what the run refined them to, and
# the ATE against the same cell run with the true calibration.
users = [r for r in rows if r["run"].endswith("+user") and "ate_rmse_m" in r]
if users:
    def med_worst(vals, digits=1):
        vals = [abs(v) for v in vals if v is not None]
        return f"{statistics.median(vals):.{digits}f} / {max(vals):.{digits}f}" if vals else "n/a"
    print()
    print("| scene | run | runs | clock error ms, calibrate / run (median / worst) | extrinsic mm, calibrate / run | "
          "extrinsic deg, calibrate / run | ATE / ATE with the truth (median / worst) |")
    print("|---|---|---|---|---|---|---|")
    for sc in scenes:
        for run in sorted({r["run"] for r in users if r["scene"] == sc}):
            rs = [r for r in users if r["scene"] == sc and r["run"] == run]
            ratios = []
            for r in rs:
                truth = [t for t in rows if t["scene"] == sc and t["seed"] == r["seed"] and t["noise"] == r["noise"]
                         and t["run"] == run[: -len("+user")] and "ate_rmse_m" in t]
                if truth and truth[0]["ate_rmse_m"] > 0:
                    ratios.append(r["ate_rmse_m"] / truth[0]["ate_rmse_m"])
            pair = lambda key, digits=1: (f'{med_worst([r.get("calib_" + key) for r in rs], digits)} → '
                                          f'{med_worst([r.get("refined_" + key, r.get("calib_" + key)) for r in rs], digits)}')
            print(f"| {sc} | {run} | {len(rs)} | {pair('clock_err_ms')} | {pair('extrinsic_err_mm')} | "
                  f"{pair('extrinsic_err_deg', 3)} | {med_worst(ratios, 2)} |")
PY
}

# Adds map_static_kept to every people run of OUT/results.jsonl whose cell was also run without
# people (both runs' maps kept), then drops the maps unless KEEP_MAPS=1 was asked for.
score_static_kept() {
  python3 - "$1" "$MMLIO" "$USER_KEEPS_MAPS" <<'PY'
import json, os, subprocess, sys
out, mmlio, user_keeps = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
path = os.path.join(out, "results.jsonl")
rows = [json.loads(l) for l in open(path) if l.strip()]
def run_dir(r, people):
    cell = f'{r["scene"]}-s{r["seed"]}-n{r["noise"]}' + (f'-p{people}' if people else "")
    return os.path.join(out, cell), os.path.join(out, cell, r["run"])
for r in rows:
    if not r.get("people") or r.get("status") != "ok":
        continue
    cell, rd = run_dir(r, r["people"])
    _, ref = run_dir(r, 0)
    files = [os.path.join(rd, "map.pcd"), os.path.join(ref, "map.pcd"), os.path.join(ref, "trajectory.tum")]
    if not all(os.path.exists(f) for f in files):
        continue
    ev = subprocess.run([mmlio, "evaluate", "--gt", os.path.join(cell, f'{r["scene"]}_gt.tum'),
                         "--est", os.path.join(rd, "trajectory.tum"), "--map", files[0], "--scenario", r["scene"],
                         "--reference-map", files[1], "--reference-est", files[2], "--json"],
                        capture_output=True, text=True)
    if ev.returncode == 0:
        r["map_static_kept"] = json.loads(ev.stdout)["map_static_kept"]
with open(path, "w") as f:
    for r in rows:
        f.write(json.dumps(r) + "\n")
if not user_keeps:
    for r in rows:
        _, rd = run_dir(r, r.get("people", 0))
        for name in os.listdir(rd) if os.path.isdir(rd) else []:
            if name.startswith("map") and name.endswith(".pcd"):
                os.remove(os.path.join(rd, name))
PY
}

if [ "${1:-}" = "--list" ]; then jobs "${2:-accuracy_out}"; exit 0; fi
if [ "${1:-}" = "--summarise" ]; then summarise "${2:-accuracy_out}"; exit 0; fi
OUT="${1:-accuracy_out}"
command -v parallel >/dev/null || { echo "accuracy.sh needs GNU parallel (Debian: apt-get install parallel)" >&2; exit 1; }
command -v bc >/dev/null || { echo "accuracy.sh needs bc (Debian: apt-get install bc)" >&2; exit 1; }
MMLIO="${MMLIO:-build/mmlio}"
[ -x "$MMLIO" ] || scripts/build.sh --target mmlio
# Two matrices in one folder would write and delete each other's bags.
if [ -e "$OUT/results.jsonl" ]; then
  echo "accuracy.sh: $OUT already holds a matrix (results.jsonl); give another folder or remove it" >&2
  exit 1
fi
mkdir -p "$OUT"
# Stopped (Ctrl-C, kill), the running cells stop too: GNU parallel would go on with them otherwise.
trap 'trap - INT TERM; pkill -TERM -P $$; wait; exit 130' INT TERM
USER_KEEPS_MAPS="${KEEP_MAPS:-0}"
[ "$PEOPLE" = 0 ] || export KEEP_MAPS=1  # score_static_kept compares the maps with and without people
jobs "$OUT" | parallel --will-cite -j "$JOBS" --line-buffer > "$OUT/results.jsonl" &
wait $!  # in the background, so that the trap above runs as soon as a signal comes
[ "$PEOPLE" = 0 ] || score_static_kept "$OUT"
summarise "$OUT"

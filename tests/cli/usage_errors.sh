#!/usr/bin/env bash
# CTest: every usage or input error of the mmlio command is one line on stderr and exit code 1
# (the README's exit codes); --help and --version exit 0. Usage: usage_errors.sh MMLIO_BINARY
set -uo pipefail
mmlio="$1"
failed=0
expect() {  # expect CODE ARGS...: exit code CODE, and for a non-zero code one "mmlio: ..." line on stderr
  local want=$1
  shift
  local err code
  err=$("$mmlio" "$@" 2>&1 >/dev/null)
  code=$?
  if [ "$code" -ne "$want" ]; then
    echo "FAIL: mmlio $* exited $code, expected $want: $err"
    failed=1
  elif [ "$want" -ne 0 ] && { [ "$(printf '%s\n' "$err" | wc -l)" -ne 1 ] || [[ "$err" != "mmlio: "* ]]; }; then
    echo "FAIL: mmlio $*: expected one 'mmlio: ' line on stderr, got: $err"
    failed=1
  fi
}
expect 0 --help
expect 0 --version
expect 0 run --help
expect 1                                   # no subcommand
expect 1 run                               # no bag
expect 1 run /nonexistent/mmlio.bag        # a path that does not exist
expect 1 run /nonexistent/mmlio.bag --no-such-flag
expect 1 bench /dev/null --replay 0        # not a positive number
expect 1 run /dev/null --duration soon     # not a number
expect 1 evaluate --gt /nonexistent.tum --est /nonexistent.tum
expect 1 info /dev/null                    # not a bag
expect 1 config                                   # neither --dump-defaults nor a file
expect 1 config --dump-defaults "$0"                # both

# config --dump-defaults is a rig file: checked, it prints the same keys and values.
tmp=$(mktemp -d)
"$mmlio" config --dump-defaults > "$tmp/defaults.yaml" || { echo "FAIL: config --dump-defaults"; failed=1; }
"$mmlio" config "$tmp/defaults.yaml" > "$tmp/checked.yaml" || { echo "FAIL: config FILE"; failed=1; }
if ! diff <(grep -v '^#' "$tmp/defaults.yaml") <(grep -v '^#' "$tmp/checked.yaml") >/dev/null; then
  echo "FAIL: mmlio config of the dumped defaults differs from them"
  failed=1
fi
printf 'odometry:\n  window_size: four\n' > "$tmp/bad.yaml"
expect 1 config "$tmp/bad.yaml"
expect 1 init /dev/null                            # not a bag

# init on a simulated rig's bag writes a config that checks, and never overwrites one unasked.
"$mmlio" -q simulate --scenario office --duration 8 --out "$tmp/sim" >/dev/null 2>&1 || { echo "FAIL: simulate"; failed=1; }
"$mmlio" init "$tmp/sim/office.bag" --out "$tmp/rig.yaml" >/dev/null || { echo "FAIL: init"; failed=1; }
"$mmlio" config "$tmp/rig.yaml" > "$tmp/rig_checked.yaml" && grep -q "topic: /velodyne_points" "$tmp/rig_checked.yaml" ||
  { echo "FAIL: init's config does not check"; failed=1; }
expect 1 init "$tmp/sim/office.bag" --out "$tmp/rig.yaml"
# ... and runs exactly as the preset does on the rig the preset describes (true calibration given).
for cfg in "$tmp/rig.yaml" "$(dirname "$0")/../../config/hvi.yaml"; do
  "$mmlio" -q run "$tmp/sim/office.bag" --config "$cfg" --calib "$tmp/sim/office_truth.yaml" --no-loop --no-progress \
    --out "$tmp/run_$(basename "$cfg" .yaml)" >/dev/null 2>&1 || true
done
if [ "$(grep -vc "^#" "$tmp/run_rig/trajectory.tum" 2>/dev/null)" -lt 30 ] || ! cmp -s "$tmp/run_rig/trajectory.tum" "$tmp/run_hvi/trajectory.tum"; then
  echo "FAIL: init's config and the preset give different trajectories"
  failed=1
fi
# evaluate --frame-from: the frame fixed by a run aligned onto its truth; the same run evaluated in it
# without further alignment scores as its own aligned evaluation.
aligned=$("$mmlio" evaluate --gt "$tmp/sim/office_gt.tum" --est "$tmp/run_hvi/trajectory.tum" --json)
fixed=$("$mmlio" evaluate --gt "$tmp/sim/office_gt.tum" --est "$tmp/run_hvi/trajectory.tum" --json \
  --frame-from "$tmp/sim/office_gt.tum" "$tmp/run_hvi/trajectory.tum")
python3 -c 'import json,sys; a,b=(json.loads(x)["ate_rmse_m"] for x in sys.argv[1:]); sys.exit(abs(a-b) > 1e-9)' \
  "$aligned" "$fixed" || { echo "FAIL: evaluate --frame-from: $aligned vs $fixed"; failed=1; }
expect 1 evaluate --gt "$tmp/sim/office_gt.tum" --est "$tmp/run_hvi/trajectory.tum" --frame-from "$tmp/sim/office_gt.tum"
# localize: a missing session, a folder that is no session, a damaged one, a bad pose hint, another rig.
expect 1 localize "$tmp/sim/office.bag"                                   # no --session
expect 1 localize "$tmp/sim/office.bag" --session /nonexistent/session
expect 1 localize "$tmp/sim/office.bag" --session "$tmp"                  # no session.yaml
session="$tmp/run_hvi/session"
expect 1 localize "$tmp/sim/office.bag" --session "$session" --initial-pose 1,2,three,0
expect 1 localize "$tmp/sim/office.bag" --session "$session" --out "$tmp/run_hvi"  # would overwrite its run
sed 's/name: velodyne/name: vlp16/' "$(dirname "$0")/../../config/hvi.yaml" > "$tmp/other_rig.yaml"
expect 1 localize "$tmp/sim/office.bag" --session "$session" --config "$tmp/other_rig.yaml"
# A run without loop closure (run_hvi: --no-loop) still leaves the keyframe clouds relocalization needs.
"$mmlio" -q localize "$tmp/sim/office.bag" --session "$session" --calib "$tmp/sim/office_truth.yaml" --no-progress \
  --out "$tmp/loc" > /dev/null 2>&1 || { echo "FAIL: localize in the session of a run without loop closure"; failed=1; }
cp -r "$session" "$tmp/damaged"
truncate -s 100 "$tmp/damaged/keyframe_clouds.pcd"
expect 1 localize "$tmp/sim/office.bag" --session "$tmp/damaged" --calib "$tmp/sim/office_truth.yaml"
rm -rf "$tmp"
exit $failed

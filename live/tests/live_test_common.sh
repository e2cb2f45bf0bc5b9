# What the live node tests (ros/tests/live_node_test.sh, ros2/tests/live_ros2_test.sh) share; sourced.
# live_test_begin PREFIX MMLIO CONFIG_DIR: a work directory ($work) removed on exit (kept with
# KEEP_WORK=1) with every process in $pids stopped; a 30 s office simulated ($bag, $truth, $gt) and
# run by `mmlio run` ($work/run) to compare the node with.
export PATH="/usr/bin:/bin:$PATH"  # ROS's and the checks' Python tools need the system python3
export PYTHONPATH="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)${PYTHONPATH:+:$PYTHONPATH}"  # live_checks.py
pids=()

live_test_begin() {
  local prefix=$1 mmlio=$2 config_dir=$3
  work=$(mktemp -d "/tmp/$prefix.XXXXXX")
  trap live_test_cleanup EXIT
  "$mmlio" -q simulate --scenario office --duration 30 --seed 5 --out "$work/sim" > /dev/null 2>&1 || fail "simulate"
  bag="$work/sim/office.bag" truth="$work/sim/office_truth.yaml" gt="$work/sim/office_gt.tum"
  "$mmlio" -q run "$bag" --config "$config_dir/hvi.yaml" --calib "$truth" --no-progress --out "$work/run" \
    > "$work/run.log" 2>&1 || fail "mmlio run"
}

live_test_cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2> /dev/null || true; done
  sleep 1
  for p in "${pids[@]}"; do kill -KILL "$p" 2> /dev/null || true; done
  [ -n "${KEEP_WORK:-}" ] || rm -rf "$work"
}

# fail WHAT: says what failed with the tail of every log, and stops.
fail() {
  echo "FAIL: $*"
  for f in "$work"/*.log "$work"/*.txt; do [ -e "$f" ] && { echo "--- $f"; tail -20 "$f"; }; done
  exit 1
}

# wait_for SECONDS COMMAND...: until COMMAND succeeds (status 1 on time-out).
wait_for() {
  local until=$((SECONDS + $1))
  shift
  until "$@" > /dev/null 2>&1; do
    [ $SECONDS -lt $until ] || return 1
    sleep 0.3
  done
}

# stop_node PID: SIGINT, as Ctrl-C; fails unless it stops within 30 s.
stop_node() {
  kill -INT "$1"
  for _ in $(seq 100); do kill -0 "$1" 2> /dev/null || return 0; sleep 0.3; done
  fail "the node did not stop on SIGINT"
}

# ate MMLIO TUM: the trajectory's ATE against $gt, metres.
ate() { "$1" evaluate --gt "$gt" --est "$2" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["ate_rmse_m"])'; }

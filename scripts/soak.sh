#!/usr/bin/env bash
# An hour live: the simulated 30 s office (out and back) looped into the ROS 1 node (a real roscore,
# `rosbag play -l`) and into the ROS 2 node (DDS, `LOOP=N ros2_play`), both at once, for MINUTES.
# Every 30 s each node's resident memory and CPU time go to OUT/ros1.csv and OUT/ros2.csv; at the end
# each node's report (OUT/ros1/, OUT/ros2/) and a verdict: the last ten minutes' peak memory and CPU
# per minute within 20 % of the first ten's. Exit 1 when either grew more. Not in CI (it takes the hour).
# Usage: scripts/soak.sh [MINUTES (60)] [OUT (soak_out)]   from the source tree, after scripts/build.sh
set -euo pipefail
MINUTES=${1:-60}
OUT=$(realpath -m "${2:-soak_out}")
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build}
export PATH="/usr/bin:/bin:$PATH"  # ROS's Python tools need the system python3
for f in "$BUILD/mmlio" "$BUILD/ros/mmlio_node" "$BUILD/ros2/mmlio_ros2" "$BUILD/ros2/ros2_play"; do
  [ -x "$f" ] || { echo "soak: $f not built (scripts/build.sh)" >&2; exit 1; }
done
[ ! -e "$OUT" ] || [ -z "$(ls -A "$OUT")" ] || { echo "soak: $OUT is not empty" >&2; exit 1; }
mkdir -p "$OUT"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT "$p" 2> /dev/null || true; done; }
trap cleanup EXIT

"$BUILD/mmlio" -q simulate --scenario office --duration 30 --seed 5 --out "$OUT/sim" > /dev/null
bag="$OUT/sim/office.bag" truth="$OUT/sim/office_truth.yaml"
config="$ROOT/config/hvi.yaml"

# sample PID CSV: every 30 s until PID ends, minutes since start, resident MB and CPU seconds so far.
sample() {
  local pid=$1 csv=$2 tick start=$SECONDS
  tick=$(getconf CLK_TCK)
  echo "minute,rss_mb,cpu_s" > "$csv"
  while kill -0 "$pid" 2> /dev/null; do
    local rss cpu
    rss=$(awk '/^VmRSS/ {print $2 / 1024}' "/proc/$pid/status" 2> /dev/null) || break
    cpu=$(awk -v t="$tick" '{print ($14 + $15) / t}' "/proc/$pid/stat" 2> /dev/null) || break
    echo "$(((SECONDS - start) / 60)).$(((SECONDS - start) % 60 * 10 / 60)),$rss,$cpu" >> "$csv"
    sleep 30
  done
}

# ROS 1: roscore on a free port, the node, the bag looped.
export ROS_HOME="$OUT/ros_home" ROS_LOG_DIR="$OUT/ros_log" ROS_IP=127.0.0.1
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$port"
roscore -p "$port" > "$OUT/roscore.log" 2>&1 &
pids+=($!)
until rostopic list > /dev/null 2>&1; do sleep 0.5; done
"$BUILD/ros/mmlio_node" _config:="$config" _calib:="$truth" _out_dir:="$OUT/ros1" > "$OUT/ros1_node.log" 2>&1 &
ros1=$!
pids+=($ros1)
rosbag play -q -l --wait-for-subscribers "$bag" > "$OUT/ros1_play.log" 2>&1 &
play1=$!
pids+=($play1)
sample "$ros1" "$OUT/ros1.csv" &

# ROS 2: the node and the bag looped into DDS as long.
export ROS_DOMAIN_ID=$((100 + $$ % 100))
"$BUILD/ros2/mmlio_ros2" --config "$config" --calib "$truth" --out-dir "$OUT/ros2" > "$OUT/ros2_node.log" 2>&1 &
ros2=$!
pids+=($ros2)
LOOP=$((MINUTES * 2 + 1)) "$BUILD/ros2/ros2_play" "$ROS_DOMAIN_ID" "$bag" 1 livox_ros_driver2/msg/CustomMsg \
  > "$OUT/ros2_play.log" 2>&1 &
play2=$!
pids+=($play2)
sample "$ros2" "$OUT/ros2.csv" &

echo "soak: $MINUTES min; memory and CPU every 30 s in $OUT/ros1.csv and $OUT/ros2.csv"
sleep $((MINUTES * 60))
kill -TERM "$play1" "$play2" 2> /dev/null || true
sleep 5
for pid in "$ros1" "$ros2"; do
  kill -INT "$pid"
  while kill -0 "$pid" 2> /dev/null; do sleep 1; done
done

python3 - "$OUT" "$MINUTES" << 'PY'
import csv, json, sys
out, minutes = sys.argv[1], float(sys.argv[2])
window = min(10.0, minutes / 3)
grew = False
for node in ("ros1", "ros2"):
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(open(f"{out}/{node}.csv"))]
    first = [r for r in rows if r["minute"] <= window]
    last = [r for r in rows if r["minute"] >= minutes - window]
    def per_minute(rs):
        return (rs[-1]["cpu_s"] - rs[0]["cpu_s"]) / max(1e-9, rs[-1]["minute"] - rs[0]["minute"])
    rss = (max(r["rss_mb"] for r in first), max(r["rss_mb"] for r in last))
    settled = [r for r in rows if window <= r["minute"] <= 2 * window]  # after the first window's warm-up
    cpu = (per_minute(first), per_minute(last))
    report = json.load(open(f"{out}/{node}/report.json"))
    inp = report["input"]
    ok = rss[1] <= 1.2 * rss[0] and cpu[1] <= 1.2 * cpu[0]
    grew |= not ok
    print(f"{node}: peak memory {rss[0]:.0f} MB in the first {window:.0f} min, {rss[1]:.0f} MB in the last; "
          f"CPU {cpu[0]:.1f} / {cpu[1]:.1f} s per minute; {report['sweeps']['processed']} sweeps, "
          f"{len(inp['time_base_jumps'])} restarts of the bag, queue drops {inp['queue_dropped']}: "
          f"{'flat' if ok else 'GREW'}")
    if settled:
        print(f"  after warm-up: peak {max(r['rss_mb'] for r in settled):.0f} MB in minutes {window:.0f}-{2 * window:.0f}; "
              f"CPU {per_minute(settled):.1f} s per minute")
sys.exit(1 if grew else 0)
PY

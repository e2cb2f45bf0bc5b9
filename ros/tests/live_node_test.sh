#!/usr/bin/env bash
# mmlio_node against the real thing (Debian ros-core): roscore on a free port, the node, `rosbag play`
# of a short simulated office bag (30 s out and back, so loops close), `rosbag record` of what the
# node publishes. Checks the topics' types and rates, the tf tree map -> odom -> imu, the ~save_map
# service, that the node's odometry equals `mmlio run`'s on the same bag and that its loop-corrected
# trajectory scores within 5 % of it, with the loops listed in its report. Then a node localizing in
# the session `mmlio run` wrote, and one killed by SIGKILL and restarted on its autosave; then a node
# started mid-motion that is fed the bag again from its start (its clock goes back); then the spinning
# LiDAR's and the IMU's drivers stopping and restarting.
# Usage: live_node_test.sh MMLIO MMLIO_NODE CONFIG_DIR
set -euo pipefail
MMLIO="$1" NODE="$2" CONFIG_DIR="$3"
source "$(dirname "$0")/../../live/tests/live_test_common.sh"
for tool in roscore rosbag rostopic rosservice; do
  command -v "$tool" > /dev/null || { echo "FAIL: $tool not found (Debian: ros-core; scripts/install-deps.sh)"; exit 1; }
done
live_test_begin mmlio-live-test "$MMLIO" "$CONFIG_DIR"
export ROS_HOME="$work/ros_home" ROS_LOG_DIR="$work/ros_log" ROS_IP=127.0.0.1  # no reliance on the host name

port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$port"
roscore -p "$port" > "$work/roscore.log" 2>&1 &
pids+=($!)
wait_for 30 rostopic list || fail "roscore did not come up on port $port"

stdbuf -oL -eL "$NODE" _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" _out_dir:="$work/node" _map_publish_period_s:=2 \
  > "$work/node.log" 2>&1 &
node_pid=$!
pids+=($node_pid)
wait_for 30 rosservice find std_srvs/Trigger || fail "the node's ~save_map service never appeared"
for t in odometry path cloud_registered map; do
  wait_for 10 rostopic info "/mmlio_node/$t" || fail "/mmlio_node/$t not advertised"
done

rosbag record -q -O "$work/out.bag" /mmlio_node/odometry /mmlio_node/path /mmlio_node/map /tf \
  > "$work/record.log" 2>&1 &
record_pid=$!
pids+=($record_pid)
subscribed() { rostopic info /mmlio_node/odometry | grep -q "record"; }
wait_for 20 subscribed || fail "rosbag record did not subscribe"
( timeout 60 rostopic echo -n 1 --noarr /mmlio_node/cloud_registered/header > "$work/cloud_header.txt" 2>&1 ) &
echo_pid=$!

rosbag play -q --wait-for-subscribers "$bag" > "$work/play.log" 2>&1 || fail "rosbag play"
wait "$echo_pid" || fail "no registered scan arrived"
grep -q "frame_id: \"odom\"" "$work/cloud_header.txt" || fail "registered scan not in the odom frame"

# The node catches up with what it queued, then saves while running, then shuts down.
sleep 3
save=$(rosservice call /mmlio_node/save_map)
echo "$save" | grep -q "success: True" || fail "~save_map: $save"
[ -s "$work/node/trajectory.tum" ] && [ -s "$work/node/map.pcd" ] && [ -s "$work/node/report.json" ] ||
  fail "~save_map wrote no trajectory, map or report"
rm -f "$work/node/trajectory.tum"
kill -INT "$record_pid"; wait "$record_pid" || true
stop_node "$node_pid"
[ -s "$work/node/trajectory.tum" ] || fail "no trajectory written on shutdown"

run_ate=$(ate "$MMLIO" "$work/run/trajectory.tum")
node_ate=$(ate "$MMLIO" "$work/node/trajectory.tum")

python3 - "$work" "$run_ate" "$node_ate" << 'PY' || fail "checks above"
import json, sys
import rosbag
from live_checks import check, finish, read_tum

work, run_ate, node_ate = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
bag = rosbag.Bag(f"{work}/out.bag")
info = bag.get_type_and_topic_info().topics
types = {t: info[t].msg_type for t in info}
check(types.get("/mmlio_node/odometry") == "nav_msgs/Odometry", f"odometry is nav_msgs/Odometry ({types.get('/mmlio_node/odometry')})")
check(types.get("/mmlio_node/path") == "nav_msgs/Path", "path is nav_msgs/Path")
check(types.get("/mmlio_node/map") == "sensor_msgs/PointCloud2", "map is sensor_msgs/PointCloud2")
check(types.get("/tf") == "tf2_msgs/TFMessage", "tf is tf2_msgs/TFMessage")

odom = [m for _, m, _ in bag.read_messages(topics=["/mmlio_node/odometry"])]
stamps = [m.header.stamp.to_sec() for m in odom]
rate = (len(stamps) - 1) / (stamps[-1] - stamps[0]) if len(stamps) > 1 else 0.0
check(rate > 9.0 and rate < 11.0, f"odometry at the sweep rate: {rate:.2f} Hz over {len(odom)} messages")
check(all(m.header.frame_id == "odom" and m.child_frame_id == "imu" for m in odom), "odometry: odom -> imu")
check(all(m.pose.covariance[0] > 0 and m.pose.covariance[35] > 0 for m in odom), "odometry carries a pose covariance")

edges = set()
for _, m, _ in bag.read_messages(topics=["/tf"]):
    for t in m.transforms:
        edges.add((t.header.frame_id, t.child_frame_id))
check(("map", "odom") in edges and ("odom", "imu") in edges, f"tf tree map -> odom -> imu ({sorted(edges)})")

paths = [m for _, m, _ in bag.read_messages(topics=["/mmlio_node/path"])]
check(len(paths) >= 5 and paths[-1].header.frame_id == "map", f"path published per keyframe in map ({len(paths)})")
keyframes = json.load(open(f"{work}/node/report.json"))["sweeps"]["keyframes"]
last = paths[-1].poses if paths else []
check(keyframes - 2 <= len(last) <= keyframes + 1, f"the last path holds the keyframes ({len(last)}; {keyframes} keyframes)")
check(len(last) > 0 and min(abs(last[-1].header.stamp.to_sec() - t) for t in stamps) < 1e-4 and
      all(a.header.stamp < b.header.stamp for a, b in zip(last, last[1:])), "... in order, at poses the odometry gave")
maps = [m for _, m, _ in bag.read_messages(topics=["/mmlio_node/map"])]
check(len(maps) >= 3 and maps[-1].width > 10000 and maps[-1].header.frame_id == "map",
      f"map refreshed ({len(maps)} clouds, last {maps[-1].width if maps else 0} points)")

node_odo = read_tum(f"{work}/node/trajectory_odometry.tum")
run_odo = read_tum(f"{work}/run/trajectory_odometry.tum")
check(node_odo == run_odo, f"node odometry == mmlio run odometry ({len(node_odo)} vs {len(run_odo)} poses)")
report = json.load(open(f"{work}/node/report.json"))
loops = report["mapping"].get("loops", [])
run_loops = json.load(open(f"{work}/run/report.json"))["mapping"].get("loops", [])
check(len(loops) >= 1 and len(loops) == len(run_loops), f"the node closed loops live ({len(loops)}; mmlio run {len(run_loops)})")
check(node_ate <= 1.05 * run_ate + 1e-4, f"node ATE {100 * node_ate:.2f} cm within 5 % of mmlio run's {100 * run_ate:.2f} cm")
check(report["input"]["queue_dropped"]["imu"] == 0 and report["input"]["queue_dropped"]["scans"] == 0, "no message dropped")
finish()
PY

# Localizing live in the session `mmlio run` left (the same bag): the node finds itself at once, its
# poses are the session's map frame's, and its report says so; its state is on /diagnostics, and a
# pose hint 50 m off (rviz's "2D Pose Estimate" on /initialpose, outside the building) is refuted
# without moving it.
stdbuf -oL -eL "$NODE" __name:=mmlio_loc _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" _out_dir:="$work/loc" \
  _session:="$work/run/session" > "$work/loc_node.log" 2>&1 &
loc_pid=$!
pids+=($loc_pid)
wait_for 30 rostopic info /mmlio_loc/odometry || fail "the localizing node never advertised its odometry"
rostopic echo /diagnostics > "$work/diagnostics.txt" 2> /dev/null &
echo_pid=$!
pids+=($echo_pid)
(sleep 8 && rostopic pub -1 /initialpose geometry_msgs/PoseWithCovarianceStamped \
  '{header: {frame_id: map}, pose: {pose: {position: {x: 50.0, y: 0.0, z: 0.0}, orientation: {w: 1.0}}}}' \
  > "$work/initialpose.log" 2>&1) &
rosbag play -q --wait-for-subscribers "$bag" > "$work/play_loc.log" 2>&1 || fail "rosbag play (localize)"
sleep 3
kill "$echo_pid" 2> /dev/null || true
stop_node "$loc_pid"
python3 - "$work" << 'PY' || fail "localization checks above"
import sys
from live_checks import check, check_found_in_session, check_in_session_frame, finish

work = sys.argv[1]
loc = check_found_in_session(work, "loc")
check(loc.get("pose_hints") == 1 and loc.get("pose_hints_refuted") == 1 and loc.get("localized_at_end") is True,
      f"the hint 50 m off was taken and refuted ({loc.get('pose_hints')}, {loc.get('pose_hints_refuted')})")
check_in_session_frame(work, "loc", "in the session's map frame, the hint notwithstanding")
diagnostics = open(f"{work}/diagnostics.txt").read()
check('name: "mmlio: localization"' in diagnostics and "level: 0" in diagnostics,
      "/diagnostics carried the localization, OK once localized")
check('name: "mmlio: input"' in diagnostics and 'message: "keeping up' in diagnostics,
      "/diagnostics carried the input's state: keeping up")
finish()
PY

# Nothing lost on a crash: autosaving every 5 s of sensor time, a node is killed with SIGKILL after
# 20 s of the bag; its last autosave is a whole session, and a node restarted on it localizes there.
stdbuf -oL -eL "$NODE" __name:=mmlio_crash _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" \
  _out_dir:="$work/crash" _autosave_period_s:=5 > "$work/crash_node.log" 2>&1 &
crash_pid=$!
pids+=($crash_pid)
wait_for 30 rostopic info /mmlio_crash/odometry || fail "the crashing node never advertised its odometry"
rosbag play -q --wait-for-subscribers -u 20 "$bag" > "$work/play_crash.log" 2>&1 || fail "rosbag play (crash)"
kill -KILL "$crash_pid"
wait "$crash_pid" 2> /dev/null || true
[ -s "$work/crash/session/session.yaml" ] || fail "no autosaved session after SIGKILL"
[ -z "$(ls -d "$work"/crash/session.* 2> /dev/null)" ] || fail "a half-written session was left beside the autosave"
stdbuf -oL -eL "$NODE" __name:=mmlio_resumed _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" \
  _out_dir:="$work/resumed" _session:="$work/crash/session" > "$work/resumed_node.log" 2>&1 &
resumed_pid=$!
pids+=($resumed_pid)
wait_for 30 rostopic info /mmlio_resumed/odometry || fail "the restarted node never advertised its odometry"
rosbag play -q --wait-for-subscribers "$bag" > "$work/play_resumed.log" 2>&1 || fail "rosbag play (resumed)"
sleep 3
stop_node "$resumed_pid"
python3 - "$work" << 'PY' || fail "crash checks above"
import json, sys
from live_checks import check, check_in_session_frame, finish

work = sys.argv[1]
saved = json.load(open(f"{work}/crash/report.json"))
check(saved["outputs"].get("session_keyframes", 0) >= 5, f"the autosave holds the keyframes so far ({saved['outputs'].get('session_keyframes')})")
loc = json.load(open(f"{work}/resumed/report.json")).get("localization", {})
check(loc.get("localized") is True and loc.get("localized_at_end") is True,
      f"the restarted node localized in the autosave ({loc.get('last_reason')})")
check_in_session_frame(work, "resumed", "past the crash point too")
finish()
PY

# A node started after the drivers, then `rosbag play` restarted: the bag from 5 s in (walking: the
# IMU is initialised without a standstill), then all of it again into the same node, its stamps 25 s
# back. The route ends where it starts, so the node goes on from where the rig is, in the same world,
# and says so.
stdbuf -oL -eL "$NODE" __name:=mmlio_again _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" \
  _out_dir:="$work/again" > "$work/again_node.log" 2>&1 &
again_pid=$!
pids+=($again_pid)
wait_for 30 rostopic info /mmlio_again/odometry || fail "the node for the replayed bag never advertised its odometry"
rosbag play -q -r 2 -s 5 --wait-for-subscribers "$bag" > "$work/play_again_1.log" 2>&1 || fail "rosbag play -s 5"
rosbag play -q -r 2 "$bag" > "$work/play_again_2.log" 2>&1 || fail "rosbag play (again)"
sleep 3
stop_node "$again_pid"
python3 -m live_checks second_pass "$work" again || fail "the replayed bag's trajectory"
again_ate=$(ate "$MMLIO" "$work/again_second.tum")
run_odo_ate=$(ate "$MMLIO" "$work/run/trajectory_odometry.tum")
python3 -m live_checks replayed "$work" again "$again_ate" "$run_odo_ate" || fail "replayed bag checks above"

# The spinning LiDAR's driver stops 12 s in for 5 s and restarts (a new publisher, its seq from 0
# again), then the IMU's 22 s in for 2 s: the node rides on the solid-state LiDAR, then on the
# LiDARs alone, and says which stream went missing, and when.
stdbuf -oL -eL "$NODE" __name:=mmlio_restart _config:="$CONFIG_DIR/hvi.yaml" _calib:="$truth" \
  _out_dir:="$work/restart" > "$work/restart_node.log" 2>&1 &
restart_pid=$!
pids+=($restart_pid)
wait_for 30 rostopic info /mmlio_restart/odometry || fail "the node for the driver restarts never advertised"
/usr/bin/python3 "$(dirname "$0")/restart_play.py" "$bag" /velodyne_points:12:5,/livox/imu:22:2 \
  > "$work/play_restart.log" 2>&1 || fail "restart_play"
sleep 3
stop_node "$restart_pid"
restart_ate=$(ate "$MMLIO" "$work/restart/trajectory_odometry.tum")
python3 -m live_checks driver_restarts "$work" restart "$restart_ate" "$run_odo_ate" || fail "driver restart checks above"
echo "PASS"

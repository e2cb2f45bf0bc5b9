#!/usr/bin/env bash
# CTest: the rviz view shows what the node publishes. Every topic in ros/rviz/mmlio.rviz is one
# mmlio_node advertises (and every message the node publishes is shown), its fixed frame is the
# node's default map frame, and `roslaunch mmlio.launch rviz:=true` starts rviz with it (and
# only then). Usage: rviz_config_test.sh ROS_DIR
set -euo pipefail
ros_dir="$1"
export ROS_PACKAGE_PATH="$ros_dir:${ROS_PACKAGE_PATH:-/usr/share}"
/usr/bin/python3 - "$ros_dir" <<'PY'
import re, sys, yaml
ros = sys.argv[1]
cfg = yaml.safe_load(open(f"{ros}/rviz/mmlio.rviz"))
shown = {d["Topic"] for d in cfg["Visualization Manager"]["Displays"] if "Topic" in d}
node = open(f"{ros}/mmlio_node.cpp").read()
advertised = {"/mmlio_node/" + t for t in re.findall(r'pnh\.advertise<[^>]+>\("([^"]+)"', node)}
failures = []
if not advertised:
    failures.append("found no advertise() in mmlio_node.cpp")
if shown - advertised:
    failures.append(f"rviz shows topics the node does not publish: {sorted(shown - advertised)}")
if advertised - shown:
    failures.append(f"published but not shown: {sorted(advertised - shown)}")
if cfg["Visualization Manager"]["Global Options"]["Fixed Frame"] != "map":
    failures.append("fixed frame is not the node's map frame")
if failures:
    print("FAIL: " + "; ".join(failures))
    sys.exit(1)
print(f"rviz shows {sorted(shown)}")
PY
with=$(roslaunch --nodes "$ros_dir/launch/mmlio.launch" rviz:=true 2>&1)
without=$(roslaunch --nodes "$ros_dir/launch/mmlio.launch" 2>&1)
grep -qx "/rviz" <<< "$with" || { echo "FAIL: rviz:=true starts no rviz: $with"; exit 1; }
if grep -qx "/rviz" <<< "$without"; then echo "FAIL: rviz starts by default"; exit 1; fi
grep -q 'args="-d $(find mmlio)/rviz/mmlio.rviz"' "$ros_dir/launch/mmlio.launch" || { echo "FAIL: launch does not pass the config"; exit 1; }
echo "roslaunch rviz:=true starts /rviz with rviz/mmlio.rviz"

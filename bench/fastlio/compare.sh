#!/usr/bin/env bash
# Speed reference: FAST-LIO2 (VI: the spinning LiDAR + the IMU) next to mmlio (HVI by default, loops)
# on the same simulated bags, each pinned to one core, in the same hour. Prints per bag the CPU
# seconds of the whole run and the ATE of both.
#
# Usage: bench/fastlio/compare.sh DIR...   (each DIR as written by `mmlio simulate --out DIR`:
#        one .bag, its *_gt.tum and *_truth.yaml)
#   POINT_FILTERS="4 3"  FAST-LIO2's point_filter_num values to run, one column each: 4 is its
#                        mapping_velodyne.launch default, 3 its accurate setting (a VLP-16 cloud lists
#                        its 16 rings column by column, so every 4th point keeps only rings 0, 4, 8
#                        and 12, while every 3rd cycles through all 16)
#   RATE=10      rosbag play rate for FAST-LIO2 (fed through roscore; it queues what it cannot
#                process at once, so nothing is lost, and CPU time, not wall time, is compared)
#   MMLIO=build/mmlio   the mmlio binary
#   MMLIO_CONFIG=FILE   mmlio's rig config (default: built-in, HVI); config/vi.yaml compares the same
#                       sensors as FAST-LIO2 (the spinning LiDAR and the IMU)
#   FASTLIO_SRC=DIR     a FAST_LIO checkout with its ikd-Tree submodule (default: cloned into
#                       build/fastlio at the commits below)
#
# FAST-LIO2 is built here without catkin, against Debian 12's ROS1 and PCL (installed on first
# use: libpcl-dev is large), with stubs for what Debian does not package (bench/fastlio/stub:
# the Livox driver's CustomMsg, FAST-LIO's Pose6D message, eigen_conversions). Its parameters are
# its mapping_velodyne.launch defaults (0.5 m scan and map voxels, 3 iterations) with the point
# filters of POINT_FILTERS.
# Measured in the README (Speed).
set -euo pipefail
# Paths given relative to where it was started from, before it moves to the repository's root.
[ -n "${MMLIO:-}" ] && MMLIO=$(realpath "$MMLIO")
mm_cfg=()  # mmlio's --config, if one is given
[ -n "${MMLIO_CONFIG:-}" ] && mm_cfg=(--config "$(realpath "$MMLIO_CONFIG")")
dirs=()
for d in "$@"; do dirs+=("$(realpath "$d")"); done
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
RATE="${RATE:-10}"
POINT_FILTERS="${POINT_FILTERS:-4 3}"
MMLIO="${MMLIO:-build/mmlio}"
FASTLIO_COMMIT=7cc4175de6f8ba2edf34bab02a42195b141027e9
IKDTREE_COMMIT=e2e3f4e9d3b95a9e66b1ba83dc98d4a05ed8a3c4
WORK="$ROOT/build/fastlio"
BIN="$WORK/fastlio_mapping"
export PATH="/usr/bin:/bin:$PATH"  # Debian's ROS tools, not a pyenv python

build() {
  local src="${FASTLIO_SRC:-$WORK/FAST_LIO}"
  if [ ! -f "$src/src/laserMapping.cpp" ]; then
    git clone -q https://github.com/hku-mars/FAST_LIO "$src"
    git -C "$src" checkout -q "$FASTLIO_COMMIT"
    git clone -q https://github.com/hku-mars/ikd-Tree "$src/include/ikd-Tree"
    git -C "$src/include/ikd-Tree" checkout -q "$IKDTREE_COMMIT"
  fi
  local need=()
  for p in libpcl-dev libpcl-conversions-dev libtf-dev libvisualization-msgs-dev python3-dev; do
    dpkg -s "$p" >/dev/null 2>&1 || need+=("$p")
  done
  if [ ${#need[@]} -gt 0 ]; then
    apt-get install -y --no-install-recommends "${need[@]}" >/dev/null
  fi
  local py
  py=$(/usr/bin/python3 -c 'import sysconfig; print(sysconfig.get_paths()["include"], sysconfig.get_config_var("LDVERSION"))')
  mkdir -p "$WORK"
  # MP_PROC_NUM=1: FAST-LIO2's own choice on a machine with fewer than four cores.
  g++ -O3 -std=c++14 -fopenmp -DMP_PROC_NUM=1 -DROOT_DIR=\"$WORK/\" \
    -I"$ROOT/bench/fastlio/stub" -I"$ROOT/include" -I"$src/include" -I/usr/include/pcl-1.13 -I/usr/include/eigen3 -I"${py% *}" \
    "$src/src/laserMapping.cpp" "$src/src/preprocess.cpp" "$src/include/ikd-Tree/ikd_Tree.cpp" -o "$BIN" \
    -lroscpp -lrosconsole -lroscpp_serialization -lrostime -lxmlrpcpp -lcpp_common -ltf -ltf2_ros -ltf2 \
    -lpcl_common -lpcl_io -lpcl_filters -lpcl_kdtree -lpcl_search -lpython"${py#* }" -lboost_system -lpthread
}

# FAST-LIO2's parameters for a simulated rig: the spinning LiDAR's topic and extrinsic from the truth
# file ($1), every $2-th point.
config() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import sys, yaml
t = yaml.safe_load(open(sys.argv[1]))
point_filter = int(sys.argv[2])
v = t["velodyne"]
T = v["T_imu_sensor"]
imu = t.get("imu", {}).get("topic", "/livox/imu")
print(f"""common: {{lid_topic: "{v.get('topic', '/velodyne_points')}", imu_topic: "{imu}", time_sync_en: false, time_offset_lidar_to_imu: 0.0}}
preprocess: {{lidar_type: 2, scan_line: 16, scan_rate: 10, timestamp_unit: 0, blind: 0.5}}
mapping: {{acc_cov: 0.1, gyr_cov: 0.1, b_acc_cov: 0.0001, b_gyr_cov: 0.0001, fov_degree: 360, det_range: 100.0,
  extrinsic_est_en: false, extrinsic_T: [{T[3]}, {T[7]}, {T[11]}],
  extrinsic_R: [{T[0]}, {T[1]}, {T[2]}, {T[4]}, {T[5]}, {T[6]}, {T[8]}, {T[9]}, {T[10]}]}}
publish: {{path_en: false, scan_publish_en: false, dense_publish_en: false, scan_bodyframe_pub_en: false}}
pcd_save: {{pcd_save_en: false, interval: -1}}
feature_extract_enable: false
point_filter_num: {point_filter}
max_iteration: 3
filter_size_surf: 0.5
filter_size_map: 0.5
cube_side_length: 1000
runtime_pos_log_enable: false""")
PY
}

# CPU seconds (user + system) a process has used so far.
cpu_of() { awk -v hz="$(getconf CLK_TCK)" '{printf "%.2f", ($14 + $15) / hz}' "/proc/$1/stat"; }

# Runs FAST-LIO2 on one bag (roscore and rosbag play on core 0, FAST-LIO2 on core 1) and prints
# its CPU seconds once it has processed everything. Between messages FAST-LIO2 polls at 5 kHz,
# about 0.13 s of CPU per second here: the bag is played fast (RATE) so that it is rarely idle, and
# it is stopped as soon as its CPU use drops to that idle rate.
run_fastlio() {
  local bag=$1 cfg=$2 out=$3
  export ROS_MASTER_URI=http://localhost:11399
  taskset -c 0 roscore -p 11399 >"$out/roscore.log" 2>&1 &
  local core=$!
  for _ in $(seq 100); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
  rosparam load "$cfg"
  (cd "$out" && taskset -c 0 rosbag record -q -O odom.bag /Odometry __name:=fastlio_rec >/dev/null 2>&1) &
  taskset -c 1 "$BIN" >"$out/fastlio.log" 2>&1 &
  local fl=$!
  sleep 2
  local before
  before=$(cpu_of "$fl")
  taskset -c 0 rosbag play -q -r "$RATE" "$bag" >/dev/null 2>&1
  local prev now
  now=$(cpu_of "$fl")
  while true; do
    sleep 2
    prev=$now
    now=$(cpu_of "$fl")
    /usr/bin/python3 -c "import sys; sys.exit(0 if $now - $prev < 0.5 else 1)" && break
  done
  kill -INT "$fl"; wait "$fl" || true
  rosnode kill /fastlio_rec >/dev/null 2>&1 || true
  sleep 2
  kill "$core"; wait "$core" 2>/dev/null || true
  /usr/bin/python3 -c "print(f'{$now - $before:.2f}')"
}

# TUM trajectory of FAST-LIO2's /Odometry (the IMU frame, as mmlio's).
odom_to_tum() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import sys, rosbag
with open(sys.argv[2], "w") as f:
    for _, m, _ in rosbag.Bag(sys.argv[1]).read_messages():
        p, q = m.pose.pose.position, m.pose.pose.orientation
        f.write(f"{m.header.stamp.to_sec():.9f} {p.x} {p.y} {p.z} {q.x} {q.y} {q.z} {q.w}\n")
PY
}

ate_cm() {
  "$MMLIO" evaluate --gt "$1" --est "$2" --json |
    /usr/bin/python3 -c 'import json, sys; print("%.2f" % (100 * json.load(sys.stdin)["ate_rmse_m"]))'
}

[ $# -gt 0 ] || { sed -n '2,/^set -euo/p' "$0" | sed '$d'; exit 2; }
[ -x "$BIN" ] || build
mode=$(basename "${MMLIO_CONFIG:-hvi}" .yaml | tr '[:lower:]' '[:upper:]')
read -r -a filters <<< "$POINT_FILTERS"
header="| bag |"; rule="|---|"
for n in "${filters[@]}"; do header="$header FAST-LIO2 VI, 1 point in ${n}: CPU s, ATE cm |"; rule="$rule---|"; done
header="$header mmlio $mode + loops: CPU s, ATE cm (odometry) |"; rule="$rule---|"
for n in "${filters[@]}"; do header="$header CPU ratio to 1 in ${n} |"; rule="$rule---|"; done
echo "$header"
echo "$rule"
for dir in "${dirs[@]}"; do
  bag=$(ls "$dir"/*.bag); gt=$(ls "$dir"/*_gt.tum); truth=$(ls "$dir"/*_truth.yaml)
  row="| $(basename "$dir") |"
  fl_cpus=()
  for n in "${filters[@]}"; do
    out="$WORK/runs/$(basename "$dir")-filter$n"
    rm -rf "$out"; mkdir -p "$out"
    config "$truth" "$n" >"$out/fastlio.yaml"
    fl_cpu=$(run_fastlio "$bag" "$out/fastlio.yaml" "$out")
    odom_to_tum "$out/odom.bag" "$out/fastlio.tum"
    row="$row $fl_cpu, $(ate_cm "$gt" "$out/fastlio.tum") |"
    fl_cpus+=("$fl_cpu")
  done
  out="$WORK/runs/$(basename "$dir")"
  mm_cpu=$(taskset -c 1 "$MMLIO" bench "$bag" "${mm_cfg[@]}" --calib "$truth" 2>&1 | sed -n 's/.*CPU \([0-9.]*\) s.*/\1/p' | head -1)
  "$MMLIO" run "$bag" "${mm_cfg[@]}" --calib "$truth" --no-progress --out "$out/mmlio" >/dev/null 2>&1
  row="$row $mm_cpu, $(ate_cm "$gt" "$out/mmlio/trajectory_odometry.tum") |"
  for c in "${fl_cpus[@]}"; do row="$row $(/usr/bin/python3 -c "print(f'{$mm_cpu / $c:.2f}')") |"; done
  echo "$row"
done

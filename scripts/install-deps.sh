#!/usr/bin/env bash
# Installs mmlio's build and test dependencies from Debian 12 packages.
# Idempotent and non-interactive: packages already present are skipped.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev libtbb-dev libnanoflann-dev
  libyaml-cpp-dev libcli11-dev libgtest-dev libbenchmark-dev nlohmann-json3-dev libbz2-dev
  zlib1g-dev libsqlite3-dev libzstd-dev liblz4-dev libfastcdr-dev libfastrtps-dev
  cyclonedds-dev cyclonedds-tools
  librosbag-storage-dev pluginlib-dev libroscpp-dev libsensor-msgs-dev libstd-msgs-dev
  libgeometry-msgs-dev libnav-msgs-dev libtf2-ros-dev libtf2-msgs-dev libstd-srvs-dev libdiagnostic-msgs-dev
  ros-core python3-rosbag python3-sensor-msgs python3-nav-msgs python3-tf2-msgs python3-std-srvs
  python3-diagnostic-msgs
  python3
  parallel bc
  clang-format clang-tidy
  libjs-three chromium
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"

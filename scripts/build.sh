#!/usr/bin/env bash
# Configures and builds mmlio in ./build (Release). Safe to run repeatedly.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
# Debian's ROS1 CMake helpers need the system Python, not a pyenv shim first on PATH.
export PATH="/usr/bin:/bin:$PATH"
JOBS="${JOBS:-2}"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build -j"$JOBS" "$@"

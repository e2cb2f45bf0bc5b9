#!/usr/bin/env bash
# CTest: `cmake --install` the build into a fresh prefix, then configure, build and run a user's
# project against it (find_package(mmlio), mmlio::pipeline) and the installed mmlio command.
# Usage: install_and_use.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 source=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export PATH="/usr/bin:/bin:$PATH"
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$source/tests/install/consumer" -B "$tmp/consumer" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/consumer" -j2 >/dev/null
"$tmp/consumer/consumer"
"$tmp/prefix/bin/mmlio" --version
test -f "$tmp/prefix/share/mmlio/config/hvi.yaml"

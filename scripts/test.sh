#!/usr/bin/env bash
# Installs dependencies, builds, checks the code format (scripts/lint.sh), and runs the whole
# test suite with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
scripts/lint.sh
cd build
ctest --output-on-failure -j2 --timeout 600

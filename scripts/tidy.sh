#!/usr/bin/env bash
# clang-tidy (Debian's 14, the checks of .clang-tidy, every finding an error) on the library's
# sources, src/*/*.cpp and the headers they include. Needs build/compile_commands.json
# (scripts/build.sh writes it). About 10 minutes on two cores.
# Usage: scripts/tidy.sh [FILE...]   (default: every library source)
set -euo pipefail
cd "$(dirname "$0")/.."
# Debian's run-clang-tidy is a python3 script: the system one, not a pyenv shim first on PATH.
export PATH="/usr/bin:/bin:$PATH"
[ -f build/compile_commands.json ] || { echo "tidy: build/compile_commands.json missing: run scripts/build.sh" >&2; exit 1; }
if [ $# -gt 0 ]; then files=("$@"); else mapfile -t files < <(git ls-files 'src/*.cpp' 2>/dev/null || find src -name '*.cpp' | sort); fi
# run-clang-tidy prints every file's command; its exit code says whether any finding was an error.
if run-clang-tidy -p build -j "$(nproc)" -quiet "${files[@]/#/$PWD/}" > build/tidy.log 2>&1; then
  echo "tidy: ${#files[@]} library sources clean (.clang-tidy)"
else
  sed 's/\x1b\[[0-9;]*m//g' build/tidy.log | grep -E "(warning|error): " | sort -u
  echo "tidy: findings above (full log: build/tidy.log)" >&2
  exit 1
fi

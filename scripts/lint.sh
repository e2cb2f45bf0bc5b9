#!/usr/bin/env bash
# The code's format as .clang-format defines it (Debian's clang-format 14): every tracked C++ file
# must already be formatted; a file that is not is named with the first differences.
# Usage: scripts/lint.sh [--fix]   (--fix formats the files in place)
set -euo pipefail
cd "$(dirname "$0")/.."
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
else
  mapfile -t files < <(find apps bench include ros src tests -name '*.cpp' -o -name '*.hpp' -o -name '*.h' | sort)
fi
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
bad=0
for f in "${files[@]}"; do
  if ! clang-format --dry-run --Werror "$f" 2>/tmp/mmlio_lint_$$.txt; then
    echo "lint: $f is not formatted (scripts/lint.sh --fix):"
    head -6 /tmp/mmlio_lint_$$.txt
    bad=1
  fi
done
rm -f /tmp/mmlio_lint_$$.txt
[ "$bad" -eq 0 ] && echo "lint: ${#files[@]} C++ files formatted as .clang-format says"
exit "$bad"

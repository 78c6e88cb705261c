#!/usr/bin/env bash
# Checks that every C++ file of the project reads as .clang-format says; names each file that
# does not, with the command that fixes it. Exit 0: all formatted; 1: some not; 2: no clang-format.
# Run by ctest as format_check (scripts/test.sh). Usage: scripts/check_format.sh [ROOT]
set -euo pipefail
root=$(cd "${1:-$(dirname "${BASH_SOURCE[0]}")/..}" && pwd)
clang_format=${CLANG_FORMAT:-clang-format}
command -v "$clang_format" >/dev/null || {
  echo "check_format: $clang_format not found (Debian: apt-get install clang-format)" >&2
  exit 2
}
cd "$root"
if [ -d .git ] && command -v git >/dev/null; then
  mapfile -t files < <(git ls-files '*.cc' '*.h')
else
  mapfile -t files < <(find app bench calibration common libnetsim libreconstruct tests \
    -name '*.cc' -o -name '*.h' | sort)
fi
# One clang-format for all files; it names each line that differs as "FILE:LINE:COL: error".
mapfile -t bad < <("$clang_format" --style=file --dry-run "${files[@]}" 2>&1 |
  sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: .*$/\1/p' | sort -u)
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: ${#bad[@]} of ${#files[@]} files differ from .clang-format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix with: clang-format -i --style=file ${bad[*]}" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files follow .clang-format"

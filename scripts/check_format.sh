#!/usr/bin/env bash
# Lists the C++ files whose layout differs from .clang-format's and exits 1 when there is one
# (CI runs it as the Style.CodeIsFormatted test). Apply the format: scripts/check_format.sh --fix
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v clang-format >/dev/null; then
  echo "check_format: clang-format is not installed (scripts/setup.sh installs Debian's clang-format)"
  exit 1
fi
if [ -d .git ] && command -v git >/dev/null; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
else
  mapfile -t files < <(find . -path ./build -prune -o -path './build-*' -prune -o -path '*/node_modules' -prune \
                              -o \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -print)
fi
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
# One clang-format for every file (one process per file took 30 s, most of it starting them): its
# --dry-run names each place that differs; each file is listed once.
if report=$(clang-format --style=file --dry-run --Werror "${files[@]}" 2>&1); then
  echo "check_format: ${#files[@]} files formatted"
  exit 0
fi
mapfile -t bad < <(grep -o '^[^:]*:[0-9]*:[0-9]*: error: code should be clang-formatted' <<<"$report" | cut -d: -f1 | sort -u)
[ ${#bad[@]} -eq 0 ] && { echo "check_format: clang-format failed: $report" | head -5; exit 1; }
for f in "${bad[@]}"; do echo "check_format: $f is not formatted (scripts/check_format.sh --fix)"; done
exit 1

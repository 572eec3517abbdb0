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
bad=0
for f in "${files[@]}"; do
  if ! clang-format --style=file "$f" | cmp -s - "$f"; then
    echo "check_format: $f is not formatted (scripts/check_format.sh --fix)"
    bad=1
  fi
done
[ $bad -eq 0 ] && echo "check_format: ${#files[@]} files formatted"
exit $bad

#!/usr/bin/env bash
# Installs what the project needs (Debian packages), builds, and runs every test with CTest.
# The README's test command; .ci/run calls it. Multi-host tests need root (network namespaces)
# and are skipped, and say so, without it.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
"$here/scripts/setup.sh"
# The independent MCAP readers the recorder's tests use: npm's @mcap/core and
# @foxglove/omgidl-serialization (versions pinned in tests/js/package-lock.json).
if ! command -v npm >/dev/null; then
  sudo_cmd=(); [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends nodejs npm
fi
(cd "$here/tests/js" && npm ci --no-audit --no-fund --loglevel=error)
status=0
ctest --test-dir "$here/build" --output-on-failure -j "$(nproc)" --timeout 600 || status=$?
# The parser and unit tests again under AddressSanitizer + UBSan (build-asan/, issue 14).
"$here/scripts/sanitize.sh" || status=1
# Processes killed by a failing test can leave Fast DDS shared-memory segments behind.
command -v fastdds >/dev/null && fastdds shm clean >/dev/null 2>&1 || true
exit $status

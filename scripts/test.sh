#!/usr/bin/env bash
# Installs what the project needs (Debian packages), builds the tests and what they start, and runs
# them with CTest, then the sanitizer stage. The README's test command; .ci/run calls it.
# Multi-host tests need root (network namespaces) and are skipped, and say so, without it.
#   scripts/test.sh          every claim, heavy ones at the smallest size that checks them
#   scripts/test.sh --full   also the full-size twins (CTest label "full"), the benchmarks' build
#                            (docs/BENCHMARKS.md and the README say what it adds)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
full=0
for arg in "$@"; do
  case "$arg" in
    --full) full=1 ;;
    -h|--help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "test.sh: error: unknown option '$arg' (known: --full, --help)" >&2; exit 2 ;;
  esac
done

build_targets=dw-tests
[ "$full" = 1 ] && build_targets=all
DW_BUILD_TARGETS=$build_targets "$here/scripts/setup.sh"
# The independent MCAP readers the recorder's tests use: npm's @mcap/core and
# @foxglove/omgidl-serialization (versions pinned in tests/js/package-lock.json).
if ! command -v npm >/dev/null; then
  sudo_cmd=(); [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends nodejs npm
fi
(cd "$here/tests/js" && npm ci --no-audit --no-fund --loglevel=error)
select=(-LE full)
[ "$full" = 1 ] && select=()
status=0
# The sanitizer stage's build compiles beside the tests under SCHED_IDLE: the kernel runs it only on
# a core no test wants this instant and preempts it at once when one does (CTest leaves about 40 %
# of the cores idle). In memory (/dev/shm), not on disk: built on disk beside them (2026-11-29,
# runs 51-55) it once made the soak fail, its recorder's memory growing 0.616 MB/min (limit 0.5) —
# suspected, not shown: the recorder's queue grows while its fdatasync waits on a disk busy writing
# back the build's 1.3 GB. nice 19 was not enough (2026-11-27: a nice-19 task still gets its slices
# against busy test threads). Where /dev/shm is small or mounted noexec, it builds after CTest.
asan_dir=""
if [ -w /dev/shm ] && [ "$(df -Pk /dev/shm | awk 'NR == 2 {print $4}')" -gt $((4 * 1024 * 1024)) ]; then
  asan_dir=$(mktemp -d /dev/shm/dw-asan.XXXXXX)
  asan_log="$asan_dir.log"
  # On any exit: the build's process group stopped (it has its own session; long gone after a
  # whole run, so a failed kill is no error: under set -e it would become the script's status).
  trap 'if [ -n "${asan_build:-}" ]; then kill -- -"$asan_build" 2>/dev/null || true; fi; rm -rf "$asan_dir" "$asan_log"' EXIT
  cp "$(type -P true)" "$asan_dir/exec-check"
  "$asan_dir/exec-check" 2>/dev/null || { rm -rf "$asan_dir"; asan_dir=""; }
fi
if [ -n "$asan_dir" ]; then
  idle=(chrt --idle 0)
  chrt --idle 0 true 2>/dev/null || idle=(nice -n 19)
  DW_ASAN_BUILD="$asan_dir" setsid "${idle[@]}" "$here/scripts/sanitize.sh" --build >"$asan_log" 2>&1 &
  asan_build=$!
fi
# The cores' idle share over CTest (/proc/stat's cpu line: user, nice, system busy; idle, iowait
# not): what the slots and the sanitizer build leave unused.
cpu_ticks() { awk '/^cpu /{print $2 + $3 + $4, $5 + $6}' /proc/stat; }
read -r busy0 idle0 < <(cpu_ticks)
start=$SECONDS
# Tests run side by side while the machine's CPU slots last (tests/CMakeLists.txt: what each takes;
# build/resources.json: how many there are).
spec="$here/build/resources.json"
slots=$(grep -o '"slots": [0-9]*' "$spec" | grep -o '[0-9]*$')
ctest --test-dir "$here/build" --output-on-failure -j "$slots" --resource-spec-file "$spec" --timeout 900 \
  "${select[@]}" || status=$?
read -r busy1 idle1 < <(cpu_ticks)
echo "test.sh: ctest: $((SECONDS - start)) s (cores idle $(((idle1 - idle0) * 100 / (busy1 - busy0 + idle1 - idle0 + 1))) %)"
# The parser and unit tests again under AddressSanitizer + UBSan (issue 14): built beside CTest in
# memory (above), run after it (the runs start DDS participants, so they follow the tests rather
# than share their slots). The history of building it beside the tests: at nice 19 (2026-11-27) a
# partition not waited out and the soak's recorder memory; on disk under SCHED_IDLE (2026-11-29,
# runs 51-55) the soak's recorder grew 0.616 MB/min (limit 0.5) in one run of five; in memory
# (2026-12-01, runs 60-61) reverted for a late SIGINT answer that run 63 then showed without it
# (docs/BENCHMARKS.md, fifth pass). Back since 2026-12-02 (the sixth pass).
start=$SECONDS
if [ -z "$asan_dir" ]; then
  "$here/scripts/sanitize.sh" || status=1
elif wait "$asan_build"; then
  echo "test.sh: sanitizer build: done beside the tests in memory (waited $((SECONDS - start)) s more)"
  DW_ASAN_BUILD="$asan_dir" "$here/scripts/sanitize.sh" --run || status=1
else
  cat "$asan_log"; echo "test.sh: the sanitizer build FAILED (its log above)"; status=1
fi
echo "test.sh: sanitizer stage: $((SECONDS - start)) s"
# Processes killed by a failing test can leave Fast DDS shared-memory segments behind.
command -v fastdds >/dev/null && fastdds shm clean >/dev/null 2>&1 || true
exit $status

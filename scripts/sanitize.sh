#!/usr/bin/env bash
# Builds the parser and unit test executables with AddressSanitizer + UndefinedBehaviorSanitizer in
# build-asan/ (a separate build directory) and runs them. scripts/test.sh (CI) calls it after the
# main tests. The process tests are left out: they start the ordinary build's executables.
#   scripts/sanitize.sh           configure, build, run
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build="$here/build-asan"
# Each run is one process. Fast DDS 2.9 numbers the participants of a process 0, 1, 2, ... and
# never reuses a number, while discovery on loopback reaches ids 0-31 (dds/config.cpp): a process
# that has created 32 participants can no longer be discovered. The PX4 tests create 2-4 each, so
# dw_planner_tests runs in shards (CTest runs every test in a process of its own anyway).
# "Nx run": N processes (GoogleTest's shards), run side by side: the planner's tests mostly wait
# on simulated time (under ASan Px4Refusals.* took 13 s of CPU in 128 s, the others 16 in 78).
# The longest first (a fresh clone, 2026-12-02: the physics 37 s, the shards 22-39 s, the file
# fuzz 14 s, the rest 1-7 s), so that no long run starts last.
runs=(dw_physics_tests "4x dw_planner_tests --gtest_filter=Px4Refusals.*"
      "3x dw_planner_tests --gtest_filter=-Px4Refusals.*" "dw_file_fuzz_tests --gtest_filter=FileFuzz.*"
      dw_mocap_tests dw_recorder_tests dw_unit_tests dw_stand_tests)
# Runs at once: the waiting shards leave the cores idle (13 s of CPU in 128 s, above), so four times
# as many as there are cores: on 2 cores the physics and the seven shards start together. In
# /work/main (2026-12-02): the runs 83 s at twice the cores, 76 s at three times, 55 s at four
# (the same 92 CPU-seconds; every run passed).
at_once=$(($(nproc) * 4))
tests=()   # the executables the runs name, built once each
shards=()  # per expanded run: "index total" (or empty)
expanded=()
for run in "${runs[@]}"; do
  n=1
  if [[ "$run" =~ ^([0-9]+)x\ (.*)$ ]]; then n=${BASH_REMATCH[1]}; run=${BASH_REMATCH[2]}; fi
  for ((i = 0; i < n; ++i)); do
    expanded+=("$run")
    if [ "$n" -gt 1 ]; then shards+=("$i $n"); else shards+=(""); fi
  done
  read -r -a cmd <<<"$run"
  [[ " ${tests[*]} " == *" ${cmd[0]} "* ]] || tests+=("${cmd[0]}")
done
# -g1: line tables, all a sanitizer report needs for file:line; full -g made each file slower to build.
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 -DDW_SANITIZE=ON \
  -DDW_BUILD_PREDICTOR=OFF -DDW_BUILD_EXPLAINER=OFF -DDW_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${tests[@]}"
# new_delete_type_mismatch=0: Debian's libfastrtps 2.9 deletes its StatisticsWriterImpl through a
# base of another size (inside the library, at every participant's destruction; not the lab's code).
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1:new_delete_type_mismatch=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS=suppressions="$here/scripts/lsan.supp"
# The runs go at_once at a time (each test process has its own DDS domain); each
# one's output is printed whole when it ends.
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
sanitize_run() {  # run index, run, shard ("index total" or empty)
  read -r -a cmd <<<"$2"
  local start=$SECONDS name="$2" env=()
  if [ -n "$3" ]; then
    read -r index total <<<"$3"
    env=(GTEST_SHARD_INDEX="$index" GTEST_TOTAL_SHARDS="$total")
    name="$2 (shard $((index + 1)) of $total)"
  fi
  if env "${env[@]}" "$build/bin/${cmd[0]}" --gtest_brief=1 "${cmd[@]:1}" >"$logs/$1.log" 2>&1; then
    echo "sanitize: $name: passed in $((SECONDS - start)) s" >>"$logs/$1.log"
  else
    echo "sanitize: $name FAILED after $((SECONDS - start)) s" >>"$logs/$1.log"; touch "$logs/$1.failed"
  fi
}
for i in "${!expanded[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$at_once" ]; do wait -n || true; done
  sanitize_run "$i" "${expanded[$i]}" "${shards[$i]}" &
done
wait
status=0
for i in "${!expanded[@]}"; do
  cat "$logs/$i.log"
  [ -e "$logs/$i.failed" ] && status=1
done
exit $status

#!/usr/bin/env bash
# Fuzzes the NatNet parsers with libFuzzer under AddressSanitizer and UndefinedBehaviorSanitizer
# (needs clang; `apt-get install clang`). Usage: scripts/fuzz.sh [seconds, default 60]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
out=$(mktemp -d)
clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$here" "$here/tests/fuzz/natnet_fuzz.cpp" "$here/mocap_bridge/natnet.cpp" "$here/core/log.cpp" \
  -o "$out/natnet_fuzz"
mkdir -p "$out/corpus"
"$out/natnet_fuzz" -max_total_time="${1:-60}" -max_len=4096 "$out/corpus" 2>&1 | tail -5

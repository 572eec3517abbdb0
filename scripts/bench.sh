#!/usr/bin/env bash
# Runs the benchmarks that feed docs/BENCHMARKS.md (after scripts/setup.sh has built them).
# Run on an otherwise idle machine; each prints a Markdown table.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
for transport in shm udp; do
  "$here/build/bin/dw-bench-pingpong" --transport "$transport" --rounds 10 --per-round 2000 2>/dev/null
  echo
done
"$here/build/bin/dw-bench-physics" --benchmark_counters_tabular=true --benchmark_color=false
"$here/build/bin/dw-bench-mcap" --dir "${DW_BENCH_DIR:-/tmp}" --benchmark_counters_tabular=true --benchmark_color=false
"$here/build/bin/dw-bench-record"
"$here/build/bin/dw-bench-stand"
"$here/build/bin/dw-bench-mocap" --seconds 60
"$here/build/bin/dw-bench-predictor"
"$here/build/bin/dw-bench-explain"
"$here/build/bin/dw-bench-security"
"$here/build/bin/dw-bench-stream" --dir "${DW_BENCH_DIR:-/tmp}"
# The soak (issue 19): 30 minutes of the simulated lab, memory, CPU and losses judged.
"$here/build/bin/dw-lab" soak --minutes 30 --out "${DW_BENCH_DIR:-/tmp}/dw-soak"

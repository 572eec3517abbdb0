#!/usr/bin/env bash
# The predictor study's wall time on a quiet machine, and beside it with one other CPU-bound
# process running (a busy loop), in one run (issue 16: loaded <= 2.5 x quiet).
# Usage: scripts/bench_study_load.sh [dw-predictor study options, e.g. --threads 2 --legs 20]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/dw-predictor
[[ -x $bin ]] || { echo "bench_study_load: $bin not built (scripts/setup.sh)" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"; [[ -n ${busy:-} ]] && kill "$busy" 2>/dev/null || true' EXIT

run() {  # prints the wall time of one study in seconds
    local start end
    start=$(date +%s.%N)
    "$bin" study --out "$out/$1" "${@:2}" >"$out/$1.log" 2>&1 || { echo "bench_study_load: study failed, see:" >&2; tail -5 "$out/$1.log" >&2; exit 1; }
    end=$(date +%s.%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }'
}

quiet=$(run quiet "$@")
bash -c 'while :; do :; done' &
busy=$!
loaded=$(run loaded "$@")
kill "$busy"; busy=
awk -v q="$quiet" -v l="$loaded" -v o="${*:-(defaults)}" 'BEGIN { printf "study %s: quiet %.1f s, with one busy process %.1f s, ratio %.2f\n", o, q, l, l / q }'

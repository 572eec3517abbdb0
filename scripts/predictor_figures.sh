#!/usr/bin/env bash
# Regenerates the figures of docs/PREDICTOR.md (issue 16): the two studies (jet merging on, and a
# plain force sum), then the single-neighbour f_d maps and the Leader Follower K=3 maps at each
# altitude the flights fly, and the regime maps. About 6 minutes on 2 cores.
# Usage: scripts/predictor_figures.sh [work folder, default /tmp/dw-predictor-figures]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/dw-predictor
[[ -x $bin ]] || { echo "predictor_figures: $bin not built (scripts/setup.sh)" >&2; exit 1; }
work=${1:-/tmp/dw-predictor-figures}
mkdir -p "$work"
[[ -f $work/study-merging/table.md ]] || "$bin" study --out "$work/study-merging" --effect jet_merging
[[ -f $work/study-sum/table.md ]] || "$bin" study --out "$work/study-sum" --no-generalisation
m=$work/study-merging
models=("$m/models/physics.yaml" "$m/models/naive_linear.json" "$m/models/learnt_linear.json" "$m/models/deep_sets.json")
for formation in single leader_follower3; do
    for altitude in 0.3 0.8 1.3; do
        "$bin" map --models "${models[@]}" --formation "$formation" --altitude "$altitude" --data "$m/flights/$formation" \
            --out "docs/predictor-$formation-$altitude.png" --line "docs/predictor-$formation-$altitude-line.png"
    done
done
cp "$m/regimes.png" docs/predictor-regimes-merging.png
cp "$work/study-sum/regimes.png" docs/predictor-regimes-sum.png
echo "tables: $m/table.md and $work/study-sum/table.md; figures in docs/"

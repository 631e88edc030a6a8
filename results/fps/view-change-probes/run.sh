#!/usr/bin/env bash
# The view-change kernel's parts and the light change's cached pass, the previous commit's
# build (BASE: a shading_bench with its libprtlab_core.so beside it) against this one (NEW),
# in alternating rounds. Usage: [FILTER=regex] run.sh BASE_DIR NEW_BENCH OUT_DIR [ROUNDS]
set -euo pipefail
BASE_DIR="$1" NEW="$2" OUT="$3" ROUNDS="${4:-2}"
export POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 POCL_AFFINITY=1
filter="${FILTER:-shading/(view_cache|cached_shade|view_cache_probe/.*)/nearest}"
for r in $(seq "$ROUNDS"); do
  for who in base new; do
    if [[ $who == base ]]; then bin="$BASE_DIR/shading_bench"; lib="$BASE_DIR"; else bin="$NEW"; lib=""; fi
    LD_LIBRARY_PATH="$lib" "$bin" --benchmark_filter="$filter" --benchmark_repetitions=5 \
      --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true \
      --benchmark_out="$OUT/$who-$r.json" --benchmark_out_format=json > "$OUT/$who-$r.txt" 2>&1
    echo "round $r $who done"
  done
done

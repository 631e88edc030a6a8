#!/usr/bin/env bash
# A/B of the cpca / cpca_sh relight (cells signal) between the commit before the BRDF-signal
# change (de7a7f4, built in a worktree) and the change (c2c29e9), same machine, same run,
# two interleaved rounds.
set -euo pipefail
PREV=${PREV:-/work/wt/base/build/release}
NEW=${NEW:-/work/main/build/release}
export POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 POCL_AFFINITY=1
for round in 1 2; do for side in previous new; do
  B=$PREV; [ $side = new ] && B=$NEW
  $B/bench/relight_bench --benchmark_min_time=0.5 --benchmark_repetitions=5 \
    --benchmark_report_aggregates_only=true \
    --benchmark_filter='relight/(cpca|cpca_sh)/(cpp|opencl)/manual_time' \
    --benchmark_out=relight-$side-round$round.json --benchmark_out_format=json
done; done

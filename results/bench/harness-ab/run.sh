#!/usr/bin/env bash
# A/B of the relight and frame hot paths: the commit before issue 13 (2c3fbd3, built in a
# worktree at $OLD) against this tree's build, interleaved in rounds so that machine noise
# hits both alike. Usage: OLD=/path/to/old/prtlab ROUNDS=3 results/bench/harness-ab/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
OLD="${OLD:?set OLD to the prtlab binary of the previous commit}"
NEW=build/release/cli/prtlab
ROUNDS="${ROUNDS:-3}"
OUT=results/bench/harness-ab
for r in $(seq 1 "$ROUNDS"); do
  for b in uncompressed bicluster; do
    "$OLD" -q compress bunny --backend $b --repeat 30 --lights 1 --json > $OUT/compress-$b-old-$r.json 2>/dev/null
    "$NEW" -q compress bunny --backend $b --repeat 30 --lights 1 --json > $OUT/compress-$b-new-$r.json 2>/dev/null
    "$OLD" -q fps bunny --backend $b --frames 20 --json > $OUT/fps-$b-old-$r.json 2>/dev/null
    "$NEW" -q fps bunny --backend $b --frames 20 --no-cull --json > $OUT/fps-$b-new-nocull-$r.json 2>/dev/null
    "$NEW" -q fps bunny --backend $b --frames 20 --json > $OUT/fps-$b-new-cull-$r.json 2>/dev/null
  done
done
/usr/bin/python3 "$(dirname "$0")/summarize.py" "$OUT" "$ROUNDS"

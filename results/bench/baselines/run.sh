#!/usr/bin/env bash
# The baselines on the bunny beside `uncompressed` and `bicluster` (defaults), in one run: ROUNDS
# rounds (default 3), each running every configuration once (`prtlab compress ... --repeat 20`: the median of 20 timed
# relights per path), in a rotated order per round so that a slow period of the machine does not
# fall on one configuration only. Writes bunny_<config>_r<round>.json here and prints the table
# (summarize.py: medians over the rounds, ratios to uncompressed's median).
# Run from the repository root after building `prtlab`.
set -euo pipefail
out=results/bench/baselines
prtlab=build/release/cli/prtlab
rounds=${ROUNDS:-3}
configs=(
  "uncompressed|--backend uncompressed"
  "bicluster|--backend bicluster"
  "csr_quantized_float32|--backend csr_quantized --param values=float32"
  "csr_quantized_float16|--backend csr_quantized --param values=float16"
  "csr_quantized_u8|--backend csr_quantized --param values=u8"
  "csr_zstd_level1|--backend csr_zstd --param level=1"
  "csr_zstd_level3|--backend csr_zstd --param level=3"
  "csr_zstd_level19|--backend csr_zstd --param level=19"
  "csr_zstd_level3_rows16384|--backend csr_zstd --param level=3 --param block_rows=16384"
)
n=${#configs[@]}
for ((round = 1; round <= rounds; ++round)); do
  for ((i = 0; i < n; ++i)); do
    entry=${configs[$(((i + round - 1) % n))]}
    name=${entry%%|*}
    # shellcheck disable=SC2086  # the arguments are words on purpose
    "$prtlab" compress bunny ${entry#*|} --json --repeat 20 > "$out/bunny_${name}_r${round}.json"
  done
done
python3 "$out/summarize.py" "$out"

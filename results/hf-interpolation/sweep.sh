#!/bin/sh
# hf-float (the btf-table's settings) over lambda and floor, geometric interpolation as hf now
# ships; one CSV/JSON per point. Run from the repository root of a clean, built tree.
set -e
tool=build/release/compressors/hf_interpolation
out=results/hf-interpolation/sweep
for lambda in 0.001 0.01 0.1 1 10; do
  $tool --out $out --configs float --lambda $lambda --tag lambda-$lambda
done
for floor in 0.1 0.01 0.0001 0.000001; do
  $tool --out $out --configs float --floor $floor --tag floor-$floor
done

#!/usr/bin/env bash
# Dense symmetric eigenproblems through LAPACK (dsyevr of Debian's serial OpenBLAS) against
# Eigen's SelfAdjointEigenSolver, one binary against itself in one run (numeric/symmetric_eigen.h:
# PRTLAB_EIGEN_SOLVER=eigen selects Eigen's solver in a build with LAPACK):
#   - every transfer backend's compression and relight: scripts/arch_ab.sh (fig6 --quick on the
#     bunny from an empty stage cache), Eigen first;
#   - the material backends: bench/material_factorization_bench (svd's texel_pca solves the
#     texels' Gram eigenproblem; cmf and hf solve none), Eigen and LAPACK interleaved, 3 rounds.
#   scripts/lapack_ab.sh [BUILD_DIR] [OUT_DIR]      (default build/release results/bench/lapack-ab)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${1:-build/release}" OUT="${2:-results/bench/lapack-ab}"
mkdir -p "$OUT"
A_ENV="PRTLAB_EIGEN_SOLVER=eigen" bash scripts/arch_ab.sh "$BUILD/cli/prtlab" "$BUILD/cli/prtlab" \
  "$OUT" eigen lapack
for round in 1 2 3; do
  for who in eigen lapack; do
    settings=""
    [[ $who == eigen ]] && settings="PRTLAB_EIGEN_SOLVER=eigen"
    # shellcheck disable=SC2086
    env $settings "$BUILD/bench/material_factorization_bench" --benchmark_filter='material/svd' \
      --benchmark_out="$OUT/material-$who-$round.json" --benchmark_out_format=json \
      > "$OUT/material-$who-$round.log" 2>&1
  done
done
python3 - "$OUT" "$BUILD" <<'PY'
import json, statistics, sys
out, build = sys.argv[1:3]
def times(who):
    t = {}
    for r in (1, 2, 3):
        for b in json.load(open(f"{out}/material-{who}-{r}.json"))["benchmarks"]:
            t.setdefault(b["name"], []).append(b["ms_per_abrdf_channel"])
    return t
e, l = times("eigen"), times("lapack")
with open(f"{out}/ab.md", "a") as o:
    o.write(f"\n## Material backends: `{build}/bench/material_factorization_bench --benchmark_filter=material/svd`, "
            "Eigen and LAPACK interleaved, 3 rounds each (median ms per ABRDF and channel, one thread)\n\n")
    o.write("| benchmark | Eigen | LAPACK | ratio |\n|---|---|---|---|\n")
    for k in e:
        me, ml = statistics.median(e[k]), statistics.median(l[k])
        o.write(f"| {k} | {me:.4f} | {ml:.4f} | {me / ml:.2f}x |\n")
    o.write("\nratio: Eigen time / LAPACK time (above 1: LAPACK faster).\n")
print(open(f"{out}/ab.md").read())
PY

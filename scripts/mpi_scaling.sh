#!/usr/bin/env bash
# Strong scaling of prtlab's MPI paths on this machine (results/mpi/; docs/distributed.md).
#   bash scripts/mpi_scaling.sh [OUT=results/mpi]
# Precompute of the chair (16,101 vertices) and `experiment run pareto --quick` on the tiny scene,
# each on 1 process (1 and all threads) and on 2 and 4 ranks of 1 thread, every run from an
# empty stage cache of its own; the bicluster search of the bunny in 1-16 row groups, and its
# groups on 2 ranks; then the cluster cost model over the recorded experiments. Writes
# OUT/precompute.jsonl, OUT/experiment.txt, OUT/bicluster-groups.jsonl and OUT/cost-model.md.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-results/mpi}"
PRTLAB=build/release/cli/prtlab
mkdir -p "$OUT"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl=self,vader OMPI_MCA_mpi_yield_when_idle=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
# The chair's mesh comes from the stage cache's derived meshes; its transfer is recomputed (--force).
"$PRTLAB" -q precompute chair > /dev/null
: > "$OUT/precompute.jsonl"
run_pre() {  # label, launcher...
  local label="$1"; shift
  local t0=$(date +%s.%N)
  "$@" -q precompute chair --force --json > "$WORK/pre.json"
  local wall=$(python3 -c "import time; print(f'{time.time() - $t0:.2f}')")
  python3 - "$label" "$wall" "$WORK/pre.json" >> "$OUT/precompute.jsonl" <<'PY'
import json, sys
label, wall, path = sys.argv[1], float(sys.argv[2]), sys.argv[3]
j = json.load(open(path))
print(json.dumps({"run": label, "wall_seconds": wall, "precompute_seconds": j["precompute_seconds"],
                  "ranks": j.get("ranks", 1), "threads": j["threads"], "data_checksum": j["data_checksum"],
                  "nnz": j["nnz"], "rank_shares": j.get("rank_shares", []), "git": j["prtlab"]["git"]}))
PY
}
run_pre "1 process, 1 thread" "$PRTLAB" --threads 1
run_pre "1 process, 2 threads" "$PRTLAB"
run_pre "2 ranks x 1 thread" mpiexec -n 2 "$PRTLAB" --threads 1
run_pre "4 ranks x 1 thread (oversubscribed)" mpiexec -n 4 "$PRTLAB" --threads 1
run_pre "2 ranks x 2 threads (oversubscribed)" mpiexec -n 2 "$PRTLAB"

: > "$OUT/experiment.txt"
run_exp() {  # label, launcher...
  local label="$1"; shift
  local t0=$(date +%s.%N)
  PRTLAB_CACHE="$WORK/cache-$RANDOM" "$@" -q --no-opencl experiment run pareto --quick \
    --scenes tiny-sphere-plane --out "$WORK/out-$RANDOM" --no-plot --force > /dev/null 2>&1
  python3 -c "import time; print(f'$label: {time.time() - $t0:.2f} s')" >> "$OUT/experiment.txt"
}
run_exp "1 process, 1 thread" "$PRTLAB" --threads 1
run_exp "1 process, 2 threads" "$PRTLAB"
run_exp "2 ranks x 1 thread" mpiexec -n 2 "$PRTLAB" --threads 1
run_exp "4 ranks x 1 thread (oversubscribed)" mpiexec -n 4 "$PRTLAB" --threads 1

# The bicluster search in row groups: what partitioning costs (computation %, storage) against the
# single search, and the groups on 2 ranks (the same result as the groups on one process).
: > "$OUT/bicluster-groups.jsonl"
run_bic() {  # label, groups, launcher...
  local label="$1" groups="$2"; shift 2
  "$@" -q --no-opencl compress bunny --backend bicluster --param "groups=$groups" --force --json \
    --no-image --lights 1 > "$WORK/bic.json"
  python3 - "$label" "$groups" "$WORK/bic.json" >> "$OUT/bicluster-groups.jsonl" <<'PY'
import json, sys
label, groups, path = sys.argv[1], int(sys.argv[2]), sys.argv[3]
j = json.load(open(path))
print(json.dumps({"run": label, "groups": groups, "compress_seconds": j["compress_seconds"],
                  "storage_bytes": j["storage_bytes"], "computation_percent": j["computation_percent"],
                  "mflops_per_relight": j["mflops_per_relight"], "git": j["prtlab"]["git"]}))
PY
}
for g in 1 2 4 8 16; do run_bic "1 process, 1 thread" "$g" "$PRTLAB" --threads 1; done
for g in 2 4; do run_bic "1 process, 2 threads" "$g" "$PRTLAB"; done
for g in 2 4; do run_bic "2 ranks x 1 thread" "$g" mpiexec -n 2 "$PRTLAB" --threads 1; done

python3 scripts/mpi_cost_model.py --tables results/table1.json results/table2.json -- \
  results/{fig6,fig8,pareto,skip,sh-biscale,sh-order,haar-light-sweep}/result.json results/cpca-paper \
  > "$OUT/cost-model.md"
echo "wrote $OUT/precompute.jsonl $OUT/experiment.txt $OUT/bicluster-groups.jsonl $OUT/cost-model.md"

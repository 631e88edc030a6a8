#!/usr/bin/env bash
# prtlab on 1, 2 and 4 MPI ranks against one process, on the tiny scene (CTest: mpi.ranks;
# docs/distributed.md). The ranks are oversubscribed on small machines.
#   ranks_test.sh PRTLAB MPIEXEC WORK_DIR
# Checks, each against the single process:
#   - precompute (T and an SH transfer): the same data checksum on 1, 2 and 4 ranks;
#   - experiment run fig6 --quick: the same points.csv, errors.csv and result.json (points and
#     failures), timing columns aside, on 2 threads and on
#     2 and 4 ranks of 2 or 3 threads against one process of 1 thread, each with a fresh stage
#     cache of its own that the ranks fill concurrently;
#   - a killed distributed run resumes to the same points.csv;
#   - node-local caches: the root measures the other ranks' points again, the same, and warns;
#   - a point that fails on a rank is recorded, the run goes on and exits 1, as one process;
#   - compress with bicluster's row groups, and srbf_cta's cluster refits, over the ranks: the
#     one-process result;
#   - four processes writing the same stage into one cache at once leave a valid entry;
#   - a command that does not spread over ranks is refused on 2 ranks.
set -euo pipefail
PRTLAB="$1" MPIEXEC="$2" WORK="$3"
HERE="$(cd "$(dirname "$0")" && pwd)"
rm -rf "$WORK" && mkdir -p "$WORK"
# Open MPI as root (CI containers), more ranks than cores, no network interfaces needed.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl=self,vader OMPI_MCA_mpi_yield_when_idle=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
mpi() { local n="$1"; shift; "$MPIEXEC" -n "$n" "$@"; }
checksum() { python3 -c 'import json,sys; print(json.load(sys.stdin)["data_checksum"])'; }
fail() { echo "FAIL: $*" >&2; exit 1; }

for sh in 0 3; do
  export PRTLAB_CACHE="$WORK/cache-pre-$sh"
  one=$("$PRTLAB" -q precompute tiny-sphere-plane --force --sh-order "$sh" --json | checksum)
  for n in 1 2 4; do
    got=$(mpi "$n" "$PRTLAB" -q precompute tiny-sphere-plane --force --sh-order "$sh" --json | checksum)
    [[ "$got" == "$one" ]] || fail "precompute (SH order $sh) on $n ranks: $got, one process: $one"
    echo "precompute, SH order $sh, $n ranks: data checksum $got (one process: the same)"
  done
  # The root's archive loads as a cache hit everywhere and is the same T.
  hit=$("$PRTLAB" -q precompute tiny-sphere-plane --sh-order "$sh" --json | checksum)
  [[ "$hit" == "$one" ]] || fail "the cached archive of a distributed precompute differs"
done

# Every rank runs a different number of threads than the single process (1 there, 2 or 3 a rank),
# so that a reduction whose grouping follows the threads, the ranks or the scheduler shows here
# on any CPU.
run() {  # run OUT CACHE THREADS [mpi N]
  local out="$1" cache="$2" threads="$3"; shift 3
  PRTLAB_CACHE="$cache" "$@" "$PRTLAB" -q --threads "$threads" experiment run fig6 --quick \
    --scenes tiny-sphere-plane --out "$out" --no-plot --no-opencl > "$out.log" 2>&1 \
    || { cat "$out.log"; fail "run into $out"; }
}
run "$WORK/one" "$WORK/cache-one" 1
# One process on more threads than the first: threads alone must not move a digit either.
run "$WORK/one-threads" "$WORK/cache-one-threads" 2
for f in points.csv errors.csv result.json; do
  python3 "$HERE/compare_points.py" "$WORK/one/fig6-quick/$f" "$WORK/one-threads/fig6-quick/$f" \
    || fail "fig6 --quick on 2 threads: $f differs from 1 thread"
done
for n in 2 4; do
  run "$WORK/ranks$n" "$WORK/cache-ranks$n" $((n == 2 ? 2 : 3)) "$MPIEXEC" -n "$n"
  for f in points.csv errors.csv result.json; do
    python3 "$HERE/compare_points.py" "$WORK/one/fig6-quick/$f" "$WORK/ranks$n/fig6-quick/$f" \
      || fail "fig6 --quick on $n ranks: $f differs from one process"
  done
  [[ -f "$WORK/ranks$n/fig6-quick/.complete" ]] || fail "$n ranks: no .complete"
done

# Stopped part-way (SIGTERM after 4 s, wherever it is; mpirun passes it to the ranks), then run
# again: the same points.
PRTLAB_CACHE="$WORK/cache-killed" timeout -s TERM 4 "$MPIEXEC" -n 2 "$PRTLAB" -q experiment run fig6 \
  --quick --scenes tiny-sphere-plane --out "$WORK/killed" --no-plot --no-opencl > /dev/null 2>&1 || true
run "$WORK/killed" "$WORK/cache-killed" 2 "$MPIEXEC" -n 2
python3 "$HERE/compare_points.py" "$WORK/one/fig6-quick/points.csv" "$WORK/killed/fig6-quick/points.csv" \
  || fail "the resumed distributed run differs"

# Node-local caches (each rank its own folder, as on nodes without a shared filesystem): the root
# finds none of the other rank's points, measures them again (the same points) and says so.
"$MPIEXEC" -n 2 bash -c 'PRTLAB_CACHE="$0/cache-local-${OMPI_COMM_WORLD_RANK:-0}" exec "$1" --threads 1 \
  experiment run fig6 --quick --scenes tiny-sphere-plane --out "$0/local" --no-plot --no-opencl' \
  "$WORK" "$PRTLAB" > "$WORK/local.log" 2>&1 || { cat "$WORK/local.log"; fail "run with node-local caches"; }
grep -q "ranks-cache-not-shared" "$WORK/local.log" \
  || { cat "$WORK/local.log"; fail "no warning when the root recomputes the ranks' points"; }
python3 "$HERE/compare_points.py" "$WORK/one/fig6-quick/points.csv" "$WORK/local/fig6-quick/points.csv" \
  || fail "node-local caches changed the points"

# A point that fails (srbf_cta refuses 13 SRBFs when it compresses, after the file was accepted)
# on whichever rank measures it: recorded as a failure, the other point measured, exit 1 with
# the failure named, the same files as one process.
cat > "$WORK/ranks-failing.toml" <<'TOML'
name = "ranks-failing"
title = "a point that fails on whichever rank measures it"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["srbf_cta"]
environments = ["courtyard"]
images = false
timing = false
[[points.srbf_cta]]
srbfs = 13
[[points.srbf_cta]]
srbfs = 12
clusters = 2
rank_light = 4
rank_vertex = 2
TOML
for n in 1 2; do
  launch=()
  [[ $n -gt 1 ]] && launch=("$MPIEXEC" -n "$n")
  if PRTLAB_CACHE="$WORK/cache-failing-$n" "${launch[@]}" "$PRTLAB" -q --no-opencl experiment run \
      "$WORK/ranks-failing.toml" --out "$WORK/failing$n" --no-plot > "$WORK/failing$n.log" 2>&1; then
    cat "$WORK/failing$n.log"; fail "a run with a failed point exited 0 ($n ranks)"
  fi
  grep -q "1 point failed, 1 measured" "$WORK/failing$n.log" \
    || { cat "$WORK/failing$n.log"; fail "the failed point is not named ($n ranks)"; }
done
for f in points.csv result.json; do
  python3 "$HERE/compare_points.py" "$WORK/failing1/ranks-failing/$f" "$WORK/failing2/ranks-failing/$f" \
    || fail "a failed point on 2 ranks: $f differs from one process"
done

# A collective compression: bicluster's row groups spread over the ranks give the one-process
# result (exact and lossy), other backends compute the same result on every rank.
export PRTLAB_CACHE="$WORK/cache-compress"
summary() { python3 -c 'import json,sys; j=json.load(sys.stdin); print(j["storage_bytes"], j["mflops_per_relight"], j["rel_l2_error_mean"], j["frobenius_rel_error"])'; }
for params in "groups=4" "groups=5 error=0.05"; do
  args=(-q --no-opencl compress tiny-sphere-plane --backend bicluster --force --json --no-image)
  for p in $params; do args+=(--param "$p"); done
  one=$("$PRTLAB" "${args[@]}" | summary)
  for n in 2 4; do
    got=$(mpi "$n" "$PRTLAB" "${args[@]}" | summary)
    [[ "$got" == "$one" ]] || fail "bicluster $params on $n ranks: $got, one process: $one"
  done
  echo "compress bicluster $params on 2 and 4 ranks: $one (one process: the same)"
done
# sh_biscale: the ranks compute the SH transfer it asks for; srbf_cta: its cluster refits spread
# over the ranks (each rank's threads taking clusters from one queue), every fit sent to all.
for backend in cpca sh_biscale srbf_cta; do
  args=(-q --no-opencl compress tiny-sphere-plane --backend "$backend" --force --json --no-image)
  [[ $backend == srbf_cta ]] && args+=(--param clusters=5 --param srbfs=162)
  one=$("$PRTLAB" --threads 1 "${args[@]}" | summary)
  got=$(mpi 2 "$PRTLAB" --threads 2 "${args[@]}" | summary)
  [[ "$got" == "$one" ]] || fail "$backend on 2 ranks: $got, one process: $one"
  echo "compress $backend on 2 ranks: $one (one process: the same)"
done

# Concurrent writers of one stage into one cache (what ranks on a shared folder do).
export PRTLAB_CACHE="$WORK/cache-shared"
for i in 1 2 3 4; do "$PRTLAB" -q precompute tiny-sphere-plane --force --sh-order 3 --json > "$WORK/w$i.json" & done
wait
one=$(checksum < "$WORK/w1.json")
for i in 2 3 4; do [[ "$(checksum < "$WORK/w$i.json")" == "$one" ]] || fail "concurrent writer $i"; done
got=$("$PRTLAB" -q precompute tiny-sphere-plane --sh-order 3 --json)
[[ "$(echo "$got" | checksum)" == "$one" ]] || fail "the shared cache entry after concurrent writes"
[[ "$(echo "$got" | python3 -c 'import json,sys; print(json.load(sys.stdin)["cache_hit"])')" == "True" ]] \
  || fail "the shared cache entry was not a hit"
[[ -z "$(find "$PRTLAB_CACHE" -name '*.tmp*')" ]] || fail "temporary files left in the cache"

# A command that does not spread over ranks is refused (on every rank, before it writes).
if mpi 2 "$PRTLAB" -q list > "$WORK/refused.log" 2>&1; then fail "prtlab list ran on 2 ranks"; fi
grep -q "run this command without mpirun" "$WORK/refused.log" || { cat "$WORK/refused.log"; fail "refusal text"; }
echo "all MPI checks passed"

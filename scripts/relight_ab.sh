#!/usr/bin/env bash
# C++ and OpenCL relight times of some backends, several builds of bench/relight_bench in one
# run, interleaved round by round (machines here are noisy: a slow period then hits every build
# alike). Each NAME=DIR names a folder holding a relight_bench and the libprtlab_core.so it was
# built with (copied from a build tree, or the build tree's bench/ with its core/ beside it).
#   scripts/relight_ab.sh OUT_DIR BACKENDS ROUNDS NAME=DIR [NAME=DIR ...]
# e.g. scripts/relight_ab.sh results/bench/relight-ab cpca,cpca_sh 5 base=/tmp/base new=build/release
# RELIGHT_AB_SUMMARY_ONLY=1 rewrites ab.md from the JSON files already in OUT_DIR. ab.md names
# each build by the git hash its binary was built at (the benchmark's context).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="$1" BACKENDS="$2" ROUNDS="$3"
shift 3
mkdir -p "$OUT"
export POCL_MAX_PTHREAD_COUNT="${POCL_MAX_PTHREAD_COUNT:-$(nproc)}"
export POCL_CPU_MAX_CU_COUNT="${POCL_CPU_MAX_CU_COUNT:-$(nproc)}"
filter="relight/($(echo "$BACKENDS" | tr ',' '|'))/"
for round in $(seq 1 "$ROUNDS"); do
  [[ -n "${RELIGHT_AB_SUMMARY_ONLY:-}" ]] && break
  for spec in "$@"; do
    name="${spec%%=*}" dir="${spec#*=}"
    bin="$dir/relight_bench" libs="$dir"
    [[ -x "$dir/bench/relight_bench" ]] && bin="$dir/bench/relight_bench" libs="$dir/core"
    PRTLAB_BENCH_BACKENDS="$BACKENDS" LD_LIBRARY_PATH="$libs" "$bin" --benchmark_filter="$filter" \
      --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
      --benchmark_out="$OUT/$name-$round.json" --benchmark_out_format=json > "$OUT/$name-$round.log" 2>&1
  done
done
python3 - "$OUT" "$ROUNDS" "$*" "$BACKENDS" <<'PY'
import json, statistics, subprocess, sys, datetime
out, rounds, specs, backends = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4]
names = [s.split("=", 1)[0] for s in specs]
ms, builds = {}, {}
for n in names:
    for r in range(1, rounds + 1):
        run = json.load(open(f"{out}/{n}-{r}.json"))
        builds[n] = run["context"].get("git_hash", "?")
        for b in run["benchmarks"]:
            if b.get("aggregate_name") == "median":
                ms.setdefault(b["run_name"], {}).setdefault(n, []).append(b["real_time"])
git = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True, text=True).stdout.strip()
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
with open(f"{out}/ab.md", "w") as o:
    o.write(f"# Relight, {' against '.join(names)}, interleaved over {rounds} rounds\n\n")
    o.write(f"- command: `scripts/relight_ab.sh {out} {backends} {rounds} {' '.join(specs)}`; run from git {git}; {cpu}; {datetime.datetime.utcnow().isoformat(timespec='seconds')}Z\n")
    o.write("- builds (each binary's build stamp): " + ", ".join(f"{n} {builds[n]}" for n in names) + "\n")
    o.write("- each cell: the median over the rounds of each round's median of 5 repetitions, ms per relight\n\n")
    o.write("| benchmark | " + " | ".join(names) + " | " + " | ".join(f"{names[0]} / {n}" for n in names[1:]) + " |\n")
    o.write("|---|" + "---|" * (2 * len(names) - 1) + "\n")
    for k, v in ms.items():
        med = [statistics.median(v[n]) for n in names]
        o.write(f"| {k.replace('/manual_time', '')} | " + " | ".join(f"{m:.3f}" for m in med) + " | " +
                " | ".join(f"{med[0] / m:.2f}x" for m in med[1:]) + " |\n")
print(open(f"{out}/ab.md").read())
PY

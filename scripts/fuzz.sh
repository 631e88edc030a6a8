#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz/, the `fuzz` preset: clang, ASan + UBSan) and runs
# each for a bounded time, starting from the seeds prtlab-fuzz-seeds writes and the kept
# regression inputs. Inputs that crash, time out or run out of memory are copied to
# tests/fuzz/regressions/<target>/, which the normal test suite replays (docs/fuzzing.md).
# The summary goes to results/fuzz/README.md (replaced atomically, with provenance).
#
#   scripts/fuzz.sh                    every target, FUZZ_SECONDS each
#   scripts/fuzz.sh mesh scene         only these targets
#
# Environment:
#   FUZZ_SECONDS    fuzzing time per target in seconds (default 30)
#   FUZZ_JOBS       build parallelism (default 2)
#   FUZZ_TIMEOUT    seconds one input may run before it counts as a hang (default 10)
#   FUZZ_RSS_MB     memory limit of the fuzzing process (default 2048)
#   FUZZ_MALLOC_MB  largest single allocation before it counts as a bug (default 2048)
#   FUZZ_RESULTS    summary file (default results/fuzz/README.md)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

SECONDS_PER_TARGET="${FUZZ_SECONDS:-30}"
JOBS="${FUZZ_JOBS:-2}"
TIMEOUT="${FUZZ_TIMEOUT:-10}"
RSS_MB="${FUZZ_RSS_MB:-2048}"
MALLOC_MB="${FUZZ_MALLOC_MB:-2048}"
RESULTS="${FUZZ_RESULTS:-$ROOT/results/fuzz/README.md}"
ALL_TARGETS=(mesh environment scene archive transfer_load material_load)
if [[ $# -gt 0 ]]; then TARGETS=("$@"); else TARGETS=("${ALL_TARGETS[@]}"); fi
for t in "${TARGETS[@]}"; do
  if [[ ! " ${ALL_TARGETS[*]} " == *" $t "* ]]; then
    echo "fuzz.sh: unknown target '$t' (targets: ${ALL_TARGETS[*]})" >&2
    exit 2
  fi
done
COMMAND="scripts/fuzz.sh${*:+ $*} (FUZZ_SECONDS=$SECONDS_PER_TARGET)"

# The project's packages (as setup.sh installs them), then clang with its libFuzzer runtime.
bash "$ROOT/scripts/setup.sh" --packages
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
if ! command -v clang++ >/dev/null 2>&1 || ! compgen -G "/usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a" >/dev/null; then
  echo "fuzz.sh: installing clang (libFuzzer)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends clang
fi

BUILD="$ROOT/build/fuzz"
cmake --preset fuzz >/dev/null
fuzzers=()
for t in "${TARGETS[@]}"; do fuzzers+=("fuzz_$t"); done
cmake --build --preset fuzz --target prtlab-fuzz-seeds "${fuzzers[@]}" -j "$JOBS"

WORK="$BUILD/tests/fuzz"
SEEDS="$WORK/seeds"
echo "fuzz.sh: writing seeds to $SEEDS"
"$WORK/prtlab-fuzz-seeds" "$SEEDS"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:intercept_tls_get_addr=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# Leaks inside third-party libraries, each explained in the file.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$ROOT/tests/fuzz/lsan.supp:print_suppressions=0}"
# PoCL, the stage cache and the targets' scratch files (left behind by a crashing input) stay
# in the build folder.
export PRTLAB_CACHE="$WORK/cache"
export TMPDIR="$WORK/tmp"
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"

rows=()
total_new=0
for t in "${TARGETS[@]}"; do
  corpus="$WORK/corpus/$t"  # grows across runs; the seeds and regressions are read-only inputs
  artifacts="$WORK/artifacts/$t"
  regressions="$ROOT/tests/fuzz/regressions/$t"
  # Artifacts of earlier runs were copied to regressions/ then: each run counts its own.
  rm -rf "$artifacts"
  mkdir -p "$corpus" "$artifacts"
  log="$WORK/fuzz_$t.log"
  inputs=("$corpus" "$SEEDS/$t")
  [[ -d "$regressions" ]] && inputs+=("$regressions")
  echo "fuzz.sh: $t for ${SECONDS_PER_TARGET} s (log $log)"
  # Fork mode keeps going after a crash, so one run reports every distinct crash it finds.
  set +e
  "$WORK/fuzz_$t" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$SECONDS_PER_TARGET" -timeout="$TIMEOUT" -rss_limit_mb="$RSS_MB" \
    -malloc_limit_mb="$MALLOC_MB" -artifact_prefix="$artifacts/" -print_final_stats=1 \
    "${inputs[@]}" >"$log" 2>&1
  rc=$?
  set -e
  # The fork-mode status lines read "#<execs>: cov: ... corp: <n> exec/s: <r> oom/timeout/crash: a/b/c ...".
  status=$(grep -E '^#[0-9]+: cov:' "$log" | tail -1 || true)
  execs=$(sed -nE 's/^#([0-9]+):.*/\1/p' <<<"$status")
  cov=$(sed -nE 's/.* cov: ([0-9]+).*/\1/p' <<<"$status")
  corp=$(sed -nE 's/.* corp: ([0-9]+).*/\1/p' <<<"$status")
  failures=$(sed -nE 's/.* oom\/timeout\/crash: ([0-9]+\/[0-9]+\/[0-9]+).*/\1/p' <<<"$status")
  if [[ -z "$status" ]]; then
    echo "fuzz.sh: $t produced no status line (exit $rc); the log ends:" >&2
    tail -20 "$log" >&2
    execs="?" cov="?" corp="?" failures="?"
  fi
  new=0
  found=()
  shopt -s nullglob
  for a in "$artifacts"/crash-* "$artifacts"/timeout-* "$artifacts"/oom-* "$artifacts"/leak-* "$artifacts"/slow-unit-*; do
    name=$(basename "$a")
    found+=("$name")
    if [[ ! -e "$regressions/$name" && ! -e "$ROOT/tests/fuzz/known/$t/$name" ]]; then
      mkdir -p "$regressions"
      cp "$a" "$regressions/$name"
      new=$((new + 1))
    fi
  done
  shopt -u nullglob
  total_new=$((total_new + new))
  rows+=("| \`$t\` | $SECONDS_PER_TARGET | ${execs:-?} | ${cov:-?} | ${corp:-?} | ${failures:-?} | ${#found[@]} | $new |")
  echo "fuzz.sh: $t: ${execs:-?} execs, oom/timeout/crash ${failures:-?}, ${#found[@]} input(s) kept, $new new"
done

# Summary, replaced atomically: written beside the destination, then renamed.
mkdir -p "$(dirname "$RESULTS")"
tmp="$(mktemp "$(dirname "$RESULTS")/.README.md.XXXXXX")"
git_hash="$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
if [[ -n "$(git -C "$ROOT" status --porcelain 2>/dev/null)" ]]; then git_hash="$git_hash (working tree modified)"; fi
cpu="$(sed -nE 's/^model name\s*:\s*//p' /proc/cpuinfo | head -1)"
{
  echo "# Fuzzing: the last run of scripts/fuzz.sh"
  echo
  echo "Written by \`scripts/fuzz.sh\` (docs/fuzzing.md); the crashes found so far, and their fixes, are"
  echo "listed in [crashes.md](crashes.md). Inputs that failed are kept in \`tests/fuzz/regressions/<target>/\`"
  echo "(replayed by the normal suite) or, while their bug is open, \`tests/fuzz/known/<target>/\`."
  echo
  echo "| target | seconds | execs | coverage | corpus | oom/timeout/crash | inputs kept | new |"
  echo "|---|---:|---:|---:|---:|---|---:|---:|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "execs, coverage (edges) and corpus are libFuzzer's last fork-mode status line; oom/timeout/crash"
  echo "counts every failing run, inputs kept the distinct failing inputs (one file each)."
  echo
  echo "## Provenance"
  echo
  echo "- command: \`$COMMAND\`"
  echo "- limits: \`-timeout=$TIMEOUT -rss_limit_mb=$RSS_MB -malloc_limit_mb=$MALLOC_MB -fork=1\`"
  echo "- git: $git_hash"
  echo "- date: $(date -u '+%Y-%m-%d %H:%M:%S UTC')"
  echo "- machine: $(uname -srm), $(nproc) cores, ${cpu:-unknown CPU}, load average $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "- compiler: $(clang++ --version | head -1)"
} >"$tmp"
mv "$tmp" "$RESULTS"
echo "fuzz.sh: summary in $RESULTS; $total_new new failing input(s)"
if [[ $total_new -gt 0 ]]; then
  echo "fuzz.sh: new inputs are in tests/fuzz/regressions/; fix the bug or move the input to tests/fuzz/known/ (docs/fuzzing.md)" >&2
  exit 1
fi

#!/usr/bin/env bash
# Builds prtlab and runs the whole test suite (README's test command; .ci/run calls this).
#   scripts/test.sh            release build + all tests
#   PRESET=asan scripts/test.sh    the same under ASan + UBSan
#   PRTLAB_ARCH=portable scripts/test.sh   the suite on the portable build (default native: this CPU;
#                                          docs/build-options.md)
# Installs missing Debian packages and the scene data first (scripts/setup.sh), so it works
# on a fresh Debian 12 machine.
set -euo pipefail
cd "$(dirname "$0")/.."
PRESET="${PRESET:-release}"
JOBS="${JOBS:-$(nproc)}"

bash scripts/setup.sh
mkdir -p build

if command -v ccache >/dev/null 2>&1 && [[ -z "${PRTLAB_COMPILER_LAUNCHER:-}" ]]; then
  export PRTLAB_COMPILER_LAUNCHER=ccache
fi
cmake --preset "$PRESET" -DPRTLAB_ARCH="${PRTLAB_ARCH:-native}" > "build/configure-$PRESET.log" 2>&1 || { cat "build/configure-$PRESET.log"; exit 1; }
cmake --build --preset "$PRESET" -j "$JOBS"

# Tests never touch the user's caches: PoCL's kernel cache and prtlab's stage cache live in the build tree.
export POCL_CACHE_DIR="$PWD/build/$PRESET/test-cache/pocl"
export PRTLAB_CACHE="$PWD/build/$PRESET/test-cache/prtlab"
export POCL_MAX_PTHREAD_COUNT="${POCL_MAX_PTHREAD_COUNT:-$JOBS}"
export POCL_CPU_MAX_CU_COUNT="${POCL_CPU_MAX_CU_COUNT:-$JOBS}"
mkdir -p "$POCL_CACHE_DIR" "$PRTLAB_CACHE"
ctest --preset "$PRESET" -j "$JOBS" --timeout 900

#!/usr/bin/env bash
# README's main command: installs what is missing, builds the release preset and runs the
# main job, writing its outputs under out/main/ (override with OUT=dir).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${OUT:-out/main}"
JOBS="${JOBS:-$(nproc)}"

bash scripts/setup.sh
if command -v ccache >/dev/null 2>&1 && [[ -z "${PRTLAB_COMPILER_LAUNCHER:-}" ]]; then
  export PRTLAB_COMPILER_LAUNCHER=ccache
fi
cmake --preset release >/dev/null
cmake --build --preset release -j "$JOBS" --target prtlab

PRTLAB=build/release/cli/prtlab
mkdir -p "$OUT"
echo "== scene info: bunny"
"$PRTLAB" scene info bunny
"$PRTLAB" scene info bunny --json > "$OUT/bunny-scene.json.tmp" && mv "$OUT/bunny-scene.json.tmp" "$OUT/bunny-scene.json"
echo "== environment: courtyard"
"$PRTLAB" env info courtyard
"$PRTLAB" env cubemap courtyard --res 32 --out "$OUT/courtyard-32.exr" --preview "$OUT/courtyard-32.png"
echo "main job done: outputs in $OUT/"
ls -l "$OUT"

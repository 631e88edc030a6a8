#!/usr/bin/env bash
# README's main command: installs what is missing, builds the release preset and runs the
# main job, writing its outputs under out/main/ (override with OUT=dir).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${OUT:-out/main}"
JOBS="${JOBS:-$(nproc)}"

bash scripts/setup.sh
mkdir -p build
if command -v ccache >/dev/null 2>&1 && [[ -z "${PRTLAB_COMPILER_LAUNCHER:-}" ]]; then
  export PRTLAB_COMPILER_LAUNCHER=ccache
fi
cmake --preset release -DPRTLAB_ARCH="${PRTLAB_ARCH:-native}" > build/configure-release.log 2>&1 || { cat build/configure-release.log; exit 1; }
cmake --build --preset release -j "$JOBS" --target prtlab

PRTLAB=build/release/cli/prtlab
mkdir -p "$OUT"
echo "== scene info: bunny"
"$PRTLAB" scene info bunny
"$PRTLAB" scene info bunny --json > "$OUT/bunny-scene.json.tmp" && mv "$OUT/bunny-scene.json.tmp" "$OUT/bunny-scene.json"
echo "== environment: courtyard"
"$PRTLAB" env info courtyard
"$PRTLAB" env cubemap courtyard --res 32 --out "$OUT/courtyard-32.exr" --preview "$OUT/courtyard-32.png"
echo "== transfer: bunny (cached after the first run)"
"$PRTLAB" precompute bunny
"$PRTLAB" -q precompute bunny --json > "$OUT/bunny-transfer.json.tmp" && mv "$OUT/bunny-transfer.json.tmp" "$OUT/bunny-transfer.json"
# The multi-backend comparison a new user should see first: every registered backend at the
# lossless bicluster's storage on the bunny (fig6's quick variant): table, images, error maps.
echo "== experiment fig6 --quick: every backend at equal storage on the bunny"
"$PRTLAB" experiment run fig6 --quick --out "$OUT" --force
echo "== backends on bunny"
for backend in $("$PRTLAB" list --json | python3 -c 'import json,sys; print(" ".join(b["name"] for b in json.load(sys.stdin)["backends"]))'); do
  echo "-- $backend"
  "$PRTLAB" compress bunny --backend "$backend"
  "$PRTLAB" -q compress bunny --backend "$backend" --json > "$OUT/bunny-$backend.json.tmp"
  mv "$OUT/bunny-$backend.json.tmp" "$OUT/bunny-$backend.json"
done

# Bi-scale rendering of the bunny under a Blender world EXR with every registered backend (the
# exact one first: the others' images are compared with it): images, error maps, frame rates and
# one table. Every backend renders, whatever its output basis (the frame loop evaluates it at the
# local bins).
ENV="${ENV:-courtyard}"
RENDERED="uncompressed $("$PRTLAB" list --json | python3 -c 'import json,sys; print(" ".join(b["name"] for b in json.load(sys.stdin)["backends"] if b["name"] != "uncompressed"))')"
for backend in $RENDERED; do
  echo "== render bunny, $backend, $ENV"
  "$PRTLAB" render bunny --backend "$backend" --env "$ENV" --filter bilinear \
    --out "$OUT/bunny-$ENV-$backend.exr" --json > "$OUT/render-$backend.json.tmp"
  mv "$OUT/render-$backend.json.tmp" "$OUT/render-$backend.json"
  "$PRTLAB" image diff "$OUT/bunny-$ENV-$backend.exr" "$OUT/bunny-$ENV-uncompressed.exr" \
    --out "$OUT/bunny-$backend-error.png" --json > "$OUT/diff-$backend.json.tmp"
  mv "$OUT/diff-$backend.json.tmp" "$OUT/diff-$backend.json"
  echo "== fps bunny, $backend"
  "$PRTLAB" fps bunny --backend "$backend" --env "$ENV" --frames 30 --json > "$OUT/fps-$backend.json.tmp"
  mv "$OUT/fps-$backend.json.tmp" "$OUT/fps-$backend.json"
done
/usr/bin/python3 scripts/main_table.py "$OUT" $RENDERED
echo "main job done: outputs in $OUT/"
ls -l "$OUT"

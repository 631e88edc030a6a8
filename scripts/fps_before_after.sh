#!/bin/bash
# View- and light-change frame rates of two builds of prtlab, interleaved scene by scene so that
# the machine's slow periods fall on both alike: the build before a change (BASE) with the
# `full` material, then the build after it (NEW) with `full`, `packed` f16 and `packed` u8.
# Each run writes <out>/<scene>-<config>.md and .json (prtlab fps); scripts/fps_table.py
# --summary-only style tables are made by the caller (results/fps/README.md).
#
#   scripts/fps_before_after.sh BASE_PRTLAB NEW_PRTLAB OUT_DIR [FRAMES] [SCENES...]
set -euo pipefail
base=$1 new=$2 out=$3 frames=${4:-20}
shift 4 || shift $#
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(bunny armor chair temple bunny-12k bunny-48k)
mkdir -p "$out"
for scene in "${scenes[@]}"; do
  for config in base-full new-full new-packed-f16 new-packed-u8; do
    bin=$new
    args=(--material full)
    case $config in
      base-full) bin=$base ;;
      new-packed-f16) args=(--material packed --material-param storage=f16) ;;
      new-packed-u8) args=(--material packed --material-param storage=u8) ;;
    esac
    "$bin" -q fps "$scene" --backend bicluster "${args[@]}" --frames "$frames" \
      --out "$out/$scene-$config.md" >/dev/null
    echo "$scene $config done"
  done
done

#!/usr/bin/env bash
# prtlab's OpenCL paths on a lent NVIDIA GPU, from the bundle scripts/gpu-bundle.sh packs (no
# Debian libraries, no network needed there): the device, the relight and shading benchmarks,
# and the frame rates of every transfer backend on the bunny, in about 8 minutes.
#   scripts/gpu-check.sh BUNDLE.tar.xz|BUNDLE_DIR [OUT_DIR]
# OUT_DIR (default results/gpu) receives <device>/: README.md (device, build, date, command, a
# table of the frame rates), devices.txt, relight.json and shading.json (Google Benchmark JSON;
# .txt: the console tables), fps-<backend>.json and the logs. Environment: GPU_CHECK_ICD, an OpenCL ICD file to use instead of one naming the
# machine's libnvidia-opencl.so.1 (to try the bundle on a machine without a GPU, e.g.
# /etc/OpenCL/vendors/pocl.icd with GPU_CHECK_DEVICE=pocl); GPU_CHECK_DEVICE (default nvidia),
# prtlab's --device; GPU_CHECK_BACKENDS (default every transfer backend); GPU_CHECK_SECONDS
# (default 480), the time the whole check may take.
set -euo pipefail
BUNDLE="${1:?usage: gpu-check.sh BUNDLE.tar.xz|BUNDLE_DIR [OUT_DIR]}"
OUT_ROOT="${2:-results/gpu}"
DEVICE="${GPU_CHECK_DEVICE:-nvidia}"
BUDGET="${GPU_CHECK_SECONDS:-480}"
start=$SECONDS
left() { echo $((BUDGET - (SECONDS - start))); }
say() { echo "gpu-check [$((SECONDS - start)) s]: $*" >&2; }

work="$(mktemp -d "${TMPDIR:-/tmp}/prtlab-gpu-check.XXXXXX")"
trap 'rm -rf "$work"' EXIT
if [[ -d "$BUNDLE" ]]; then
  B="$(cd "$BUNDLE" && pwd)"
else
  tar -C "$work" -xJf "$BUNDLE"
  B="$work/prtlab-gpu"
fi
[[ -x "$B/prtlab" ]] || { echo "gpu-check: $BUNDLE is not a prtlab GPU bundle" >&2; exit 2; }

# The OpenCL vendor: an ICD file naming the NVIDIA library by its path on this machine.
mkdir -p "$work/vendors"
if [[ -n "${GPU_CHECK_ICD:-}" ]]; then
  cp "$GPU_CHECK_ICD" "$work/vendors/"
else
  ldc="$(command -v ldconfig || echo /sbin/ldconfig)"
  lib="$("$ldc" -p 2>/dev/null | awk '$1 == "libnvidia-opencl.so.1" && !found {print $NF; found = 1}' || true)"
  for d in /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/local/nvidia/lib64 /usr/lib/wsl/lib; do
    [[ -z "$lib" && -e "$d/libnvidia-opencl.so.1" ]] && lib="$d/libnvidia-opencl.so.1"
  done
  [[ -n "$lib" ]] || { echo "gpu-check: no libnvidia-opencl.so.1 on this machine (set GPU_CHECK_ICD)" >&2; exit 2; }
  echo "$lib" > "$work/vendors/nvidia.icd"
fi
export OCL_ICD_VENDORS="$work/vendors"
export PRTLAB_DATA="$B/data" PRTLAB_SCENES="$B/scenes" PRTLAB_CACHE="$work/cache"
export PRTLAB_DEVICE="$DEVICE" PRTLAB_DEVICE_STRICT=1  # the benchmarks never fall back to the CPU
P=("$B/prtlab" --device "$DEVICE" --strict-device)

"${P[@]}" devices > "$work/devices.txt" 2>&1 || { cat "$work/devices.txt" >&2; echo "gpu-check: no OpenCL device '$DEVICE'" >&2; exit 1; }
name="$(awk -F': ' '/^selected/ {print $2; exit}' "$work/devices.txt" | sed 's/^[0-9]*:[0-9]* //')"
[[ -n "$name" ]] || name="$(sed -n 's/^ *\*\? *[0-9]*:[0-9]* //p' "$work/devices.txt" | head -1)"
[[ -n "$name" ]] || name="$DEVICE"
slug="$(echo "$name" | tr -cs 'A-Za-z0-9' '-' | sed 's/^-//; s/-$//' | cut -c1-60)"
OUT="$OUT_ROOT/$slug"
mkdir -p "$OUT"
cp "$work/devices.txt" "$OUT/devices.txt"
say "device: $name -> $OUT"

run() {  # run NAME SECONDS COMMAND...: its stdout to OUT/NAME, its stderr to OUT/NAME.log
  local name="$1" secs="$2"; shift 2
  (( secs > 0 )) || { say "$name skipped: no time left"; return 0; }
  if timeout "$secs" "$@" > "$OUT/$name" 2> "$OUT/$name.log"; then
    say "$name done"
  else
    say "$name failed or ran out of its $secs s (see $OUT/$name.log)"
  fi
}

run precompute.json "$(left)" "${P[@]}" -q precompute bunny --json
# Benchmarks: the OpenCL paths and their C++ references, short repetitions.
bench=(--benchmark_min_time=0.2 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
       --benchmark_out_format=json)
backends="${GPU_CHECK_BACKENDS:-$("${P[@]}" list --json 2>/dev/null | awk '/"materials"/ {done = 1} !done && /^      "name": "/ {gsub(/[",]/, "", $2); print $2}' | tr '\n' ' ' || true)}"
[[ -n "$backends" ]] || backends="uncompressed csr_quantized bicluster cpca cpca_sh haar sh_biscale srbf_cta"
run relight.txt $(( $(left) / 3 )) env PRTLAB_BENCH_BACKENDS="${backends// /,}" "$B/relight_bench" \
  --benchmark_filter='relight/' "${bench[@]}" --benchmark_out="$OUT/relight.json"
run shading.txt $(( $(left) / 3 )) "$B/shading_bench" "${bench[@]}" --benchmark_out="$OUT/shading.json"
for b in $backends; do
  run "fps-$b.json" "$(left)" "${P[@]}" -q fps bunny --backend "$b" --frames 20 --json
done

{
  echo "# prtlab on $name"
  echo
  echo "Written by \`scripts/gpu-check.sh\` ($(date -u +%Y-%m-%dT%H:%M:%SZ)) from a bundle of"
  echo "\`scripts/gpu-bundle.sh\`: $(cat "$B/VERSION") (git $(sed -n 's/.*(\([0-9a-f]*\)[-,].*/\1/p' "$B/VERSION"));"
  echo "device \`$DEVICE\`; $(nproc) CPU cores; $(uname -sr). Files: \`devices.txt\`,"
  echo "\`relight.json\` and \`shading.json\` (Google Benchmark, 3 repetitions of 0.2 s; the console"
  echo "tables in \`relight.txt\`, \`shading.txt\`),"
  echo "\`fps-<backend>.json\` (\`prtlab fps bunny --frames 20\`), each with its \`.log\`."
  echo
  echo "| backend | fps JSON | view change / light change fps |"
  echo "|---|---|---|"
  for b in $backends; do
    f="$OUT/fps-$b.json"
    if [[ -s "$f" ]]; then
      v="$(awk '/"view_change": \{/ {f = 1} f && /"fps": [0-9]/ {gsub(/[^0-9.]/, "", $2); printf "%.1f", $2; exit}' "$f")"
      l="$(awk '/"light_change": \{/ {f = 1} f && /"fps": [0-9]/ {gsub(/[^0-9.]/, "", $2); printf "%.1f", $2; exit}' "$f")"
      echo "| \`$b\` | \`fps-$b.json\` | ${v:-?} / ${l:-?} |"
    else
      echo "| \`$b\` | (none: see \`fps-$b.json.log\`) | |"
    fi
  done
} > "$OUT/README.md"
say "wrote $OUT in $((SECONDS - start)) s"

#!/usr/bin/env bash
# Packs what scripts/gpu-check.sh runs on a machine with an NVIDIA GPU that has none of Debian's
# libraries and no network: a portable build of prtlab, relight_bench and shading_bench, every
# shared library they load (glibc and its loader included, so the host's glibc version does not
# matter), the ocl-icd OpenCL loader, the scene files and the bunny's data.
#   scripts/gpu-bundle.sh [OUT.tar.xz]        (default build/gpu-bundle.tar.xz)
# Builds in build/gpu-bundle: PRTLAB_ARCH=portable (the device's CPU is unknown), no MPI, no
# LAPACK (OpenBLAS alone is 35 MB; the benchmarks' eigenproblems are small), no tests. The
# archive stays under the 64 MiB a device run may carry (checked). Data comes from the local
# data folder that scripts/setup.sh --data fills (PRTLAB_DATA).
set -euo pipefail
OUT="$(realpath -m "${1:-$(dirname "$0")/../build/gpu-bundle.tar.xz}")"
DATA="$(realpath -m "${PRTLAB_DATA:-${XDG_CACHE_HOME:-$HOME/.cache}/prtlab/data}")"
cd "$(dirname "$0")/.."
BUILD=build/gpu-bundle
for f in meshes/bunny00.off envmaps/courtyard.exr; do
  [[ -f "$DATA/$f" ]] || { echo "gpu-bundle: $DATA/$f is missing (run scripts/setup.sh --data)" >&2; exit 1; }
done
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPRTLAB_ARCH=portable \
  -DPRTLAB_MPI=OFF -DPRTLAB_LAPACK=OFF -DPRTLAB_BUILD_TESTS=OFF -DPRTLAB_BUILD_BENCH=ON \
  ${PRTLAB_COMPILER_LAUNCHER:+-DCMAKE_CXX_COMPILER_LAUNCHER=$PRTLAB_COMPILER_LAUNCHER} > /dev/null
cmake --build "$BUILD" --target prtlab relight_bench shading_bench

stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
root="$stage/prtlab-gpu"
mkdir -p "$root/bin" "$root/lib" "$root/data/meshes" "$root/data/envmaps"
bins=("$BUILD/cli/prtlab" "$BUILD/bench/relight_bench" "$BUILD/bench/shading_bench")
cp "${bins[@]}" "$root/bin/"
# Every library the binaries load, by the path this machine resolves, under its soname.
for b in "${bins[@]}"; do
  ldd "$b" | awk '$2 == "=>" && $3 ~ /^\// && $1 !~ /\// {print $1, $3} $1 ~ /^\/.*ld-linux/ {print "LOADER", $1}'
done | sort -u | while read -r name path; do
  if [[ $name == LOADER ]]; then
    cp -L "$path" "$root/lib/ld-linux-x86-64.so.2"
  else
    cp -L "$path" "$root/lib/$name"
  fi
done
# dlopen'ed, not in ldd: the ocl-icd loader finds vendors itself; PoCL is not carried (the GPU
# is what the bundle is for); glibc's own helpers the loader may open; TBB's allocator.
ldc="$(command -v ldconfig || echo /sbin/ldconfig)"
for extra in libOpenCL.so.1 libdl.so.2 libpthread.so.0 librt.so.1 libtbbmalloc.so.2; do
  p="$("$ldc" -p | awk -v n="$extra" '$1 == n && /x86-64/ && !found {print $NF; found = 1}' || true)"
  [[ -n "$p" && ! -f "$root/lib/$extra" ]] && cp -L "$p" "$root/lib/$extra"
done
cp -r scenes "$root/scenes"
cp "$DATA/meshes/bunny00.off" "$root/data/meshes/"
cp "$DATA"/envmaps/*.exr "$root/data/envmaps/"
cp scripts/gpu-check.sh "$root/"
"$BUILD/cli/prtlab" --version > "$root/VERSION"
# How each binary runs: through the carried loader and libraries.
for b in prtlab relight_bench shading_bench; do
  cat > "$root/$b" <<EOF
#!/usr/bin/env bash
here="\$(cd "\$(dirname "\$0")" && pwd)"
exec "\$here/lib/ld-linux-x86-64.so.2" --library-path "\$here/lib" "\$here/bin/$b" "\$@"
EOF
  chmod +x "$root/$b"
done
mkdir -p "$(dirname "$OUT")"
tmp="$OUT.tmp.$$"
trap 'rm -rf "$stage" "$tmp"' EXIT
tar -C "$stage" -cJf "$tmp" prtlab-gpu
mv "$tmp" "$OUT"
bytes=$(stat -c %s "$OUT")
echo "gpu-bundle: $OUT, $((bytes / 1024 / 1024)) MiB ($(cat "$root/VERSION"))"
if (( bytes > 60 * 1024 * 1024 )); then
  echo "gpu-bundle: $OUT is over 60 MiB: a device run carries 64 MiB in all" >&2
  exit 1
fi

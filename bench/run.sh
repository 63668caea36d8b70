#!/usr/bin/env bash
# bench/run.sh [CASE.json] [RANKS] [coloc run options...]
# Install what is missing, build, and run the main job: by default benchmark 1
# (bench/cases/case1.json) on 2 ranks, writing out/case1/report.json.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${COLOC_BUILD_DIR:-$root/build}
case=${1:-$root/bench/cases/case1.json}
ranks=${2:-2}
shift $(( $# > 2 ? 2 : $# ))
"$root/cmake/setup.sh" "$build"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
name=$(basename "$case" .json)
mpiexec -n "$ranks" --bind-to none "$build/coloc" run "$case" --out "$root/out/$name" "$@"

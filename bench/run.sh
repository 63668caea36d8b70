#!/usr/bin/env bash
# bench/run.sh                       benchmark 1 on 1 and 2 ranks + its plot (the main job)
# bench/run.sh CASE.json [RANKS] [coloc run options...]   any case
# Installs what is missing, builds, runs, and says where the report went.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${COLOC_BUILD_DIR:-$root/build}
# Only the coloc binary: the tests and microbenchmarks are built by tests/run.sh, in the same
# configuration (cmake/setup.sh), so nothing built here is compiled again there.
COLOC_BUILD_TARGETS=coloc "$root/cmake/setup.sh" "$build"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
export OMPI_MCA_mpi_yield_when_idle=${OMPI_MCA_mpi_yield_when_idle:-1}  # ranks may share cores (README)
run() { mpiexec -n "$1" --bind-to none "$build/coloc" run "${@:2}"; }

if [[ $# -ge 1 ]]; then
  case=$1
  ranks=${2:-2}
  shift $(( $# >= 2 ? 2 : 1 ))
  name=$(basename "$case" .json)
  run "$ranks" "$case" --out "$root/out/$name" "$@"
  exit 0
fi

# The main job: benchmark 1 (one particle crossing a process boundary), serial and parallel,
# and the paper's figure with both runs on the same axes.
case=$root/bench/cases/case1.json
# (--overwrite: a second bench/run.sh replaces the runs of the first)
run 1 "$case" --out "$root/out/case1-np1" --overwrite
run 2 "$case" --out "$root/out/case1-np2" --overwrite
/usr/bin/python3 "$root/bench/scripts/plot_case1.py" "$root/out/case1-np1/series.csv" \
  "$root/out/case1-np2/series.csv" --labels SEQ PAR --out "$root/out/case1.png"
echo "bench/run.sh: reports in out/case1-np1/report.json and out/case1-np2/report.json," \
     "time series in out/case1-np*/series.csv, figure in out/case1.png"

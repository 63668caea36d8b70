#!/usr/bin/env bash
# bench/run.sh [coloc run options...]            benchmark 1 on 1 and 2 ranks + its plot (the main job)
# bench/run.sh CASE [RANKS] [coloc run options...]   any case (default 2 ranks)
#
#   bench/run.sh                                  -> out/case1-np1/, out/case1-np2/, out/case1.png
#   bench/run.sh --set run.end_time=0.3           the main job with overrides (both runs)
#   bench/run.sh bench/cases/case2-small.json     CASE: a file (here, or from the repository root),
#                                                 or a name in bench/cases:
#   bench/run.sh case2-small 4 --set run.steps=20 -> out/case2-small-np4/
#   bench/run.sh case2-small 4 --out out/c2 --overwrite    (--out, --overwrite, --restart, --quiet,
#                                                            --set: coloc run's own options)
# Installs what is missing, builds the coloc binary, runs, and says where the report went. The
# output goes under out/ of the current folder (the repository root in the README).
#
# Timing: the runs are benchmarks, so a rank waiting in MPI is left to Open MPI's default (it
# polls: no OMPI_MCA_mpi_yield_when_idle) unless there are more ranks than cores; an
# OMPI_MCA_mpi_yield_when_idle already in the environment is kept and warned of. report.json
# provenance.mpi_env records what the run had (docs/benchmarks.md).
# Environment: COLOC_BUILD_DIR (default: build/ of the repository) is built and used;
# COLOC_BINARY=PATH runs that binary and builds nothing (the tests).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [[ -n ${COLOC_BINARY:-} ]]; then
  coloc=$COLOC_BINARY
else
  build=${COLOC_BUILD_DIR:-$root/build}
  # Only the coloc binary: the tests and microbenchmarks are built by tests/run.sh, in the same
  # configuration (cmake/setup.sh), so nothing built here is compiled again there.
  COLOC_BUILD_TARGETS=coloc "$root/cmake/setup.sh" "$build"
  coloc=$build/coloc
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
cores=$(nproc)
out=out

usage() {
  echo "usage: bench/run.sh [coloc run options...]                (benchmark 1 on 1 and 2 ranks)" >&2
  echo "       bench/run.sh CASE [RANKS] [coloc run options...]  (CASE: a file or a name in bench/cases)" >&2
  exit 2
}

# run RANKS CASE OPTIONS...: mpiexec, with yield only where ranks share cores.
run() {
  local n=$1
  shift
  local env=()
  if [[ -n ${OMPI_MCA_mpi_yield_when_idle:-} ]]; then
    echo "bench/run.sh: note: OMPI_MCA_mpi_yield_when_idle=$OMPI_MCA_mpi_yield_when_idle from" \
         "the environment (kept; timings with ranks on cores of their own are slower with 1)"
  elif ((n > cores)); then
    echo "bench/run.sh: note: $n ranks on $cores cores: oversubscribed, waiting ranks yield their" \
         "core (OMPI_MCA_mpi_yield_when_idle=1; the timings measure sharing, not the code)"
    env=(OMPI_MCA_mpi_yield_when_idle=1)
  fi
  env "${env[@]}" mpiexec -n "$n" --bind-to none "$coloc" run "$@"
}

# has OPTION ARGS...: whether ARGS name OPTION (alone or as OPTION=VALUE); the script then adds
# none of its own (coloc run refuses an option given twice).
has() {
  local o=$1 a
  shift
  for a in "$@"; do
    [[ $a == "$o" || $a == "$o"=* ]] && return 0
  done
  return 1
}

if [[ $# -ge 1 && $1 != -* ]]; then
  case=$1
  shift
  if [[ ! -f $case ]]; then
    # a path from the repository root (as the README writes them), or a name in bench/cases
    for c in "$root/$case" "$root/bench/cases/$case" "$root/bench/cases/$case.json"; do
      [[ -f $c ]] && { case=$c; break; }
    done
  fi
  [[ -f $case ]] || { echo "bench/run.sh: no case file '$case' (nor bench/cases/$case.json)" >&2; usage; }
  ranks=2
  if [[ $# -ge 1 && $1 =~ ^[0-9]+$ ]]; then
    ranks=$1
    shift
  elif [[ $# -ge 1 && $1 != -* ]]; then
    echo "bench/run.sh: '$1' is not a rank count (a whole number) nor an option of coloc run" >&2
    usage
  fi
  ((ranks >= 1)) || { echo "bench/run.sh: RANKS must be at least 1" >&2; usage; }
  name=$(basename "$case" .json)
  dir=$out/$name-np$ranks
  opts=()
  has --out "$@" || opts=(--out "$dir")
  run "$ranks" "$case" "${opts[@]}" "$@"
  has --out "$@" || echo "bench/run.sh: report in $dir/report.json, time series in $dir/series.csv," \
                       "log in $dir/log.txt"
  exit 0
fi

# The main job: benchmark 1 (one particle crossing a process boundary), serial and parallel,
# and the paper's figure with both runs on the same axes. Options go to both runs.
if has --out "$@"; then
  echo "bench/run.sh: the main job writes out/case1-np1 and out/case1-np2; --out is for" \
       "bench/run.sh CASE [RANKS] --out DIR" >&2
  usage
fi
case=$root/bench/cases/case1.json
# (--overwrite: a second bench/run.sh replaces the runs of the first)
again=(--overwrite)
has --overwrite "$@" && again=()
run 1 "$case" --out "$out/case1-np1" "${again[@]}" "$@"
run 2 "$case" --out "$out/case1-np2" "${again[@]}" "$@"
/usr/bin/python3 "$root/bench/scripts/plot_case1.py" "$out/case1-np1/series.csv" \
  "$out/case1-np2/series.csv" --labels SEQ PAR --out "$out/case1.png"
echo "bench/run.sh: reports in $out/case1-np1/report.json and $out/case1-np2/report.json," \
     "time series in $out/case1-np*/series.csv, figure in $out/case1.png"

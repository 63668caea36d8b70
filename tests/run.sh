#!/usr/bin/env bash
# tests/run.sh — what CI runs (.ci/run): install what is missing, build with warnings as errors
# (-DCOLOC_WERROR=ON), check the C++ style against .clang-format (cmake/format.sh; --fix repairs
# it), and run every test through CTest; then the SimGrid SMPI build's tests (label smpi: coloc
# at 64 simulated ranks against the serial run; cmake/setup-smpi.sh builds it in build-smpi,
# docs/smpi.md; COLOC_SMPI=0 skips it); then the unit, MPI and I/O tests again under
# AddressSanitizer + UndefinedBehaviorSanitizer (a second build in build-sanitize;
# COLOC_SANITIZE=0 skips it). clang-tidy is not run here (too slow for every push): CONTRIBUTING.md.
# Extra arguments go to the first ctest run (e.g. -L validation, -R halo, -L quick) and skip the
# SMPI and sanitizer passes. At the end it prints how long each part took.
#
# CTest runs 2 x cores tests at once (COLOC_TEST_JOBS overrides): most tests spend their time in
# mpirun's start and end and in waits, not on a core (docs/architecture.md, "Test time").
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${COLOC_BUILD_DIR:-$root/build}
jobs=${COLOC_TEST_JOBS:-$((2 * $(nproc)))}
parts=()
t0=$SECONDS
mark() {  # mark NAME: the part that just ended took (now - last mark) seconds
  parts+=("$(printf '%-34s %5d s' "$1" $((SECONDS - t0)))")
  t0=$SECONDS
}
summary() {
  echo "tests/run.sh: time by part"
  printf '  %s\n' "${parts[@]}"
}
trap summary EXIT

"$root/cmake/setup.sh" "$build" -DCOLOC_WERROR=ON
mark "install + build"
"$root/cmake/format.sh"
mark "clang-format check"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
export OMPI_MCA_odls_base_sigkill_timeout=0
(cd "$build" && ctest --output-on-failure -j "$jobs" "$@")
mark "tests"

if [[ ${COLOC_SMPI:-1} != 0 && $# -eq 0 ]]; then
  echo "tests/run.sh: the SimGrid SMPI build's tests ($root/build-smpi)"
  "$root/cmake/setup-smpi.sh" "$root/build-smpi" -DCOLOC_WERROR=ON -DCOLOC_REFERENCE_BUILD="$build"
  mark "SMPI: install + hypre + build"
  (cd "$root/build-smpi" && ctest --output-on-failure -j "$jobs" -L smpi)
  mark "SMPI tests"
fi

if [[ ${COLOC_SANITIZE:-1} != 0 && $# -eq 0 ]]; then
  sbuild=$root/build-sanitize
  echo "tests/run.sh: unit, mpi and io tests under AddressSanitizer + UBSan ($sbuild)"
  # -O1 -g1 (line tables): what AddressSanitizer's documentation recommends, and it compiles in
  # about half the time of -O2 -g. Only the executables of the labels it runs are built
  # (COLOC_TEST_LABELS), and the libraries as unity builds (CMAKE_UNITY_BUILD: a folder's sources
  # compiled a few at a time, each header parsed once a batch): what the sanitizers check is the
  # same code, in 25 % less compile time (docs/architecture.md, "Test time").
  "$root/cmake/setup.sh" "$sbuild" -DCOLOC_SANITIZE=ON -DCOLOC_WERROR=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DCOLOC_BUILD_BENCHMARKS=OFF \
    -DCMAKE_UNITY_BUILD=ON "-DCOLOC_TEST_LABELS=unit;mpi;io"
  mark "sanitizer build"
  # Open MPI's own allocations are reported as leaks at exit: leak checking is off.
  export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  (cd "$sbuild" && ctest --output-on-failure -j "$jobs" -L '^(unit|mpi|io)$')
  mark "sanitizer tests"
fi

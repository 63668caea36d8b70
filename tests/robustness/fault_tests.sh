#!/usr/bin/env bash
# fault_tests.sh TEST COLOC FAULTS MPIEXEC PYTHON CASE WORKDIR [ARGS] — every failure ends every
# rank (docs/robustness.md), on the tiny bed case, 2 ranks. COLOC is the driver, FAULTS its test
# build with the failure-injection hook (tests/robustness/fault_hook.cpp).
#
#   inject POINT KIND CODE   a failure on rank 1 only at fault point POINT (step 3 in the loop):
#                            every rank stops within seconds, the message is printed once, the
#                            exit status is CODE, no stale report.json is left (a planted one
#                            marked ok is gone; a report, if written, says "failed")
#   layout                   blocks of one cell on one rank (issue 15): exit 2, the key named
#   outfile                  --out under a regular file: exit 4, "Not a directory"
#   readonly                 --out on a read-only file system (a tmpfs remounted ro): exit 4
#   diskfull                 output every step onto a 2 MB tmpfs until it is full: exit 4 with
#                            "No space left on device" or the space check's message; the last
#                            checkpoint is good, series.csv holds whole rows, no .tmp left
#   fsize                    a file-size limit (ulimit -f) below the checkpoint's size: exit 4,
#                            no checkpoint.h5 and no .tmp left
#   sigterm                  SIGTERM to rank 1 only, mid-run: both ranks stop after the same step,
#                            exit 143, report.json "interrupted" with the checkpoint, which
#                            restarts and ends bitwise as the uninterrupted run
#   signal2                  two SIGTERMs: exit 143 at once, no report
set -u
test=$1 coloc=$2 faults=$3 mpiexec=$4 py=$5 case=$6 work=$7
shift 7
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
skip() { echo "SKIP: $*"; exit 77; }
wait_s=2
# run BIN OUT [args...]: 2 ranks, time-limited; output in $OUT.log, status in $rc, seconds in $secs
run() {
  local bin=$1 out=$2
  shift 2
  local t0=$SECONDS
  timeout 60 "$mpiexec" -n 2 --bind-to none "$bin" run "$case" --out "$out" --quiet \
    --set run.failure_wait_s=$wait_s "$@" > "$out.log" 2>&1
  rc=$? secs=$((SECONDS - t0))
  [[ $rc -eq 124 ]] && { cat "$out.log"; fail "timed out (hang): $*"; }
  return 0
}
# the error is printed once (lines starting "coloc: error:"), containing $2
once() {
  local n
  n=$(grep -c "^coloc: error:" "$1")
  [[ $n -eq 1 ]] || { cat "$1"; fail "the error was printed $n times (expected once)"; }
  grep -qF -- "$2" "$1" || { cat "$1"; fail "message does not contain: $2"; }
}
status_is() {  # report.json $1 has status $2
  "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(d['status']!=sys.argv[2])" \
    "$1" "$2" || fail "$1: status is not $2"
}
common=(--set run.steps=6 --set output.interval_steps=2 --set output.checkpoint_interval=2)

case $test in
  inject)
    point=$1 kind=$2 code=$3 step=3
    case $point in outdir | setup | restart) step=0 ;; output | checkpoint | series) step=4 ;; esac
    extra=()
    if [[ $point == restart ]]; then
      run "$coloc" "$work/base" --set run.steps=2 --set output.checkpoint_interval=2
      [[ $rc -eq 0 ]] || { cat "$work/base.log"; fail "base run failed"; }
      extra=(--restart "$work/base/checkpoint.h5")
    fi
    mkdir -p "$work/a" && echo '{"status": "ok", "stale": true}' > "$work/a/report.json"
    COLOC_FAULT="$point:1:$step:$kind" run "$faults" "$work/a" "${common[@]}" "${extra[@]}"
    cat "$work/a.log"
    echo "exit $rc after $secs s"
    [[ $rc -eq $code ]] || fail "exit status $rc, expected $code"
    once "$work/a.log" "injected fault at $point, step $step, rank 1"
    [[ $secs -le $((wait_s + 20)) ]] || fail "took $secs s to stop"
    if [[ -f $work/a/report.json ]]; then status_is "$work/a/report.json" failed; fi
    ls "$work/a" | grep -q '\.tmp$' && fail "a .tmp file was left: $(ls "$work/a")"
    ;;
  layout)
    run "$coloc" "$work/a" --set 'domain.cells=[4,4,3]' --set 'domain.length=[0.01,0.01,0.0075]' \
      --set 'particles.sources=[]' --set 'partition.dims=[1,1,2]'
    [[ $rc -eq 2 ]] || { cat "$work/a.log"; fail "exit $rc, expected 2"; }
    once "$work/a.log" "partition.dims: the fluid needs blocks of at least 2 cells"
    status_is "$work/a/report.json" failed
    ;;
  outfile)
    touch "$work/file"
    run "$coloc" "$work/file/out"
    [[ $rc -eq 4 ]] || { cat "$work/a.log"; fail "exit $rc, expected 4"; }
    once "$work/file/out.log" 2>/dev/null || true
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test $*"

#!/usr/bin/env bash
# fault_tests.sh TEST COLOC FAULTS MPIEXEC PYTHON CASE WORKDIR [ARGS] — every failure ends every
# rank (docs/robustness.md), on the tiny bed case, 2 ranks. COLOC is the driver, FAULTS its test
# build with the failure-injection hook (tests/robustness/fault_hook.cpp).
#
#   inject POINT KIND CODE   a failure on rank 1 only at fault point POINT (step 3 in the loop):
#                            every rank stops within seconds, the message is printed once, the
#                            exit status is CODE, no stale report.json is left (a planted one
#                            marked ok is gone; a report, if written, says "failed")
#   blowup                   a blow-up: exit 3, report.json "failed" with the failed state
#   oom KIND RANK            an allocation failing on RANK (bad_alloc in coloc's code on every
#                            rank, or abort: hypre's MPI_Abort(-1) on rank 1): exit 3, "out of
#                            memory", report.json "failed" with out_of_memory, no failed
#                            checkpoint
#   layout                   blocks of one cell on one rank (issue 15): exit 2, the key named
#   outfile                  --out under a regular file: exit 4, "Not a directory"
#   readonly                 --out on a read-only file system (a tmpfs remounted ro): exit 4
#   diskfull                 output every step onto a 2 MB tmpfs until it is full: exit 4 with
#                            "No space left on device" or the space check's message; the last
#                            checkpoint is good, series.csv holds whole rows, no .tmp left
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
# run BIN OUT [args...]: 2 ranks, time-limited; output in $log ($work/NAME.log), status in $rc,
# seconds in $secs
run() {
  local bin=$1 out=$2
  shift 2
  local t0=$SECONDS
  log="$work/$(basename "$out").log"
  timeout 60 "$mpiexec" -n 2 --bind-to none "$bin" run "$case" --out "$out" --quiet \
    --set run.failure_wait_s=$wait_s "$@" > "$log" 2>&1
  rc=$? secs=$((SECONDS - t0))
  [[ $rc -eq 124 ]] && { cat "$log"; fail "timed out (hang): $*"; }
  return 0
}
# a tmpfs of $2 at $1 (root only: CI and this machine run as root), or the test is skipped
tmpfs() {
  mkdir -p "$1" && mount -t tmpfs -o "size=$2" tmpfs "$1" 2> /dev/null ||
    skip "cannot mount a tmpfs here (needs root)"
  trap "umount '$1' 2> /dev/null" EXIT
}
# every .h5 in $1 opens and every series.csv row is whole
files_good() {
  "$py" - "$1" <<'PYEOF' || fail "files left in $1 are not whole"
import glob, os, sys, h5py
d = sys.argv[1]
for f in glob.glob(os.path.join(d, "*.h5")):
    with h5py.File(f, "r") as h:
        list(h.keys())
p = os.path.join(d, "series.csv")
if os.path.exists(p):
    text = open(p).read()
    assert text.endswith("\n"), "series.csv ends inside a row"
    rows = text.splitlines()
    n = len(rows[0].split(","))
    assert all(len(r.split(",")) == n for r in rows), "a row of series.csv is cut"
    print("series.csv:", len(rows) - 1, "rows")
PYEOF
  [[ ${2:-} == keep-tmp ]] && return 0
  ls "$1" | grep -q '\.tmp$' && fail "a .tmp file was left in $1: $(ls "$1" | grep tmp)"
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
    point=$1 kind=$2 code=$3 step=3 rank=1
    case $point in outdir | setup | restart) step=0 ;; output | checkpoint | series) step=4 ;; esac
    case $point in report) step=6 ;; esac
    case $point in outdir | series) rank=0 ;; esac  # points that only rank 0 reaches
    extra=()
    if [[ $point == restart ]]; then
      run "$coloc" "$work/base" --set run.steps=2 --set output.checkpoint_interval=2
      [[ $rc -eq 0 ]] || { cat "$work/base.log"; fail "base run failed"; }
      extra=(--restart "$work/base/checkpoint.h5")
    fi
    mkdir -p "$work/a" && echo '{"status": "ok", "stale": true}' > "$work/a/report.json"
    # --overwrite: the planted report stands for an earlier run's, replaced on purpose
    COLOC_FAULT="$point:$rank:$step:$kind" run "$faults" "$work/a" "${common[@]}" "${extra[@]}" \
      --overwrite
    cat "$log"
    echo "exit $rc after $secs s"
    [[ $rc -eq $code ]] || fail "exit status $rc, expected $code"
    once "$log" "injected fault at $point, step $step, rank $rank"
    [[ $secs -le $((wait_s + 20)) ]] || fail "took $secs s to stop"
    case $point in
      outdir | setup | restart)
        # before the run has started: --overwrite leaves the earlier run's files (the planted
        # report) as they were (issue 50), and says so where the ranks agreed on the failure (a
        # stop through the deadline, MPI_Abort, says nothing more)
        grep -q '"stale": true' "$work/a/report.json" ||
          fail "the earlier run's report was replaced or removed before the new run had started"
        grep -q "did not join the error check" "$log" ||
          once "$log" "are left as they were (--overwrite removes them only once the new run is set up)"
        ;;
      *) if [[ -f $work/a/report.json ]]; then status_is "$work/a/report.json" failed; fi ;;
    esac
    # a rank stopped by the deadline (MPI_Abort) may leave a .tmp, never a partial file under
    # the real name; the next run in the folder removes it
    files_good "$work/a" keep-tmp
    run "$coloc" "$work/a" --set run.steps=1 --overwrite
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the next run in the folder failed"; }
    files_good "$work/a"
    ;;
  oom)
    # oom KIND RANK: an allocation that fails on RANK (1, or all) in the fluid phase of step 3,
    # in coloc's own code (bad_alloc on every rank: they agree, exit 3; on one rank alone it is
    # any one-rank failure, inject above) or inside hypre (abort on rank 1: hypre's
    # MPI_Abort(-1), caught by the driver: exit 3 from that rank, which ends the job); both
    # print "out of memory" and leave report.json "failed" with out_of_memory = true
    kind=$1 rank=$2
    mkdir -p "$work/a" && echo '{"status": "ok", "stale": true}' > "$work/a/report.json"
    COLOC_FAULT="fluid:$rank:3:$kind" run "$faults" "$work/a" "${common[@]}" --overwrite
    cat "$log"
    echo "exit $rc after $secs s"
    [[ $rc -eq 3 ]] || fail "exit status $rc, expected 3"
    grep -q "out of memory" "$log" || fail "no 'out of memory' in the output"
    [[ $secs -le $((wait_s + 20)) ]] || fail "took $secs s to stop"
    status_is "$work/a/report.json" failed
    "$py" -c 'import json,sys; r=json.load(open(sys.argv[1])); sys.exit(0 if r.get("out_of_memory") is True and r.get("exit_code")==3 else 1)' \
      "$work/a/report.json" || fail "report.json lacks out_of_memory = true and exit_code 3"
    [[ -f $work/a/checkpoint.failed.h5 ]] && fail "a failed checkpoint was written out of memory"
    run "$coloc" "$work/a" --set run.steps=1 --overwrite
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the next run in the folder failed"; }
    files_good "$work/a"
    ;;
  blowup)
    # an inlet far too fast: exit 3, report.json "failed" naming the failed state, which exists
    mkdir -p "$work/a" && echo '{"status": "ok", "stale": true}' > "$work/a/report.json"
    run "$coloc" "$work/a" "${common[@]}" --set "fluid.boundary.zlo.velocity=[0,0,5]" --overwrite
    cat "$log"
    [[ $rc -eq 3 ]] || fail "exit $rc, expected 3"
    once "$log" "exceeds fluid.cfl_max"
    status_is "$work/a/report.json" failed
    "$py" - "$work/a/report.json" <<'PYEOF' || fail "report.json of the blow-up"
import json, os, sys
d = json.load(open(sys.argv[1]))
assert d["exit_code"] == 3 and "the run failed in step" in d["error"], d
assert d["checkpoint"].endswith("checkpoint.failed.h5") and os.path.exists(d["checkpoint"]), d
PYEOF
    files_good "$work/a"
    ;;
  layout)
    run "$coloc" "$work/a" --set 'domain.cells=[4,4,3]' --set 'domain.length=[0.01,0.01,0.0075]' \
      --set 'particles.sources=[]' --set 'partition.dims=[1,1,2]'
    cat "$log"
    [[ $rc -eq 2 ]] || fail "exit $rc, expected 2"
    once "$log" "partition.dims: the fluid needs blocks of at least 2 cells"
    status_is "$work/a/report.json" failed
    ;;
  outfile)
    touch "$work/file"
    run "$coloc" "$work/file/out"
    cat "$log"
    [[ $rc -eq 4 ]] || fail "exit $rc, expected 4"
    once "$log" "cannot create directory '$work/file/out': Not a directory"
    ;;
  readonly)
    tmpfs "$work/ro" 1m
    mount -o remount,ro "$work/ro" || skip "cannot remount read-only"
    run "$coloc" "$work/ro/out"
    cat "$log"
    [[ $rc -eq 4 ]] || fail "exit $rc, expected 4"
    once "$log" "Read-only file system"
    ;;
  diskfull)
    # output every step and a checkpoint every 2 onto 2 MB: it fills within ~30 steps
    tmpfs "$work/fs" 2m
    run "$coloc" "$work/fs/a" --set run.steps=400 --set output.interval_steps=1 \
      --set output.checkpoint_interval=2
    cat "$log"
    [[ $rc -eq 4 ]] || fail "exit $rc, expected 4"
    once "$log" "No space left on device"
    files_good "$work/fs/a"
    [[ -f $work/fs/a/checkpoint.h5 ]] || fail "no checkpoint kept"
    if [[ -f $work/fs/a/report.json ]]; then status_is "$work/fs/a/report.json" failed; fi
    ;;
  sigterm)
    # SIGTERM to rank 1 only (what a batch system sends to every task; here one, so that the
    # decision must be collective), mid-run
    out=$work/a
    "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" --out "$out" \
      --set run.steps=100000 --set output.checkpoint_file=ck_{step}.h5 > "$work/a.log" 2>&1 &
    mpi=$!
    ranks=()
    for _ in $(seq 50); do
      sleep 0.2
      mapfile -t ranks < <(pgrep -P "$mpi")
      [[ ${#ranks[@]} -eq 2 ]] && grep -q "^coloc: case" "$work/a.log" && break
    done
    [[ ${#ranks[@]} -eq 2 ]] || { kill "$mpi"; fail "the ranks did not start"; }
    sleep 1
    # rank 1: the child of mpirun with OMPI_COMM_WORLD_RANK=1
    for p in "${ranks[@]}"; do
      tr '\0' '\n' < "/proc/$p/environ" | grep -qx "OMPI_COMM_WORLD_RANK=1" && kill -TERM "$p"
    done
    wait "$mpi"
    rc=$?
    cat "$work/a.log"
    [[ $rc -eq 143 ]] || fail "exit $rc, expected 143"
    grep -q "coloc: stopped by SIGTERM after step" "$work/a.log" || fail "no stop message"
    status_is "$out/report.json" interrupted
    step=$("$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['run']['steps'])" \
      "$out/report.json")
    ck=$(printf "%s/ck_%06d.h5" "$out" "$step")
    [[ -f $ck ]] || fail "no final checkpoint $ck"
    echo "stopped after step $step"
    # the checkpoint restarts, and ends as the uninterrupted run that checkpoints at that step
    # too (a checkpoint re-sorts the particles: the same cadence gives the same bits)
    n=$((step + 2))
    opts=(--set run.steps=$n --set output.checkpoint_interval=$step
          --set output.checkpoint_file=ck_{step}.h5)
    run "$coloc" "$work/full" "${opts[@]}"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "uninterrupted run failed"; }
    run "$coloc" "$work/b" "${opts[@]}" --restart "$ck"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "restart from the interrupted checkpoint failed"; }
    last=$(printf "ck_%06d.h5" "$n")
    "$py" "$here/compare_checkpoints.py" "$work/full/$last" "$work/b/$last" ||
      fail "the restart differs from the uninterrupted run"
    ;;
  signal2)
    COLOC_FAULT="fluid:1:3:signal2" run "$faults" "$work/a" "${common[@]}"
    cat "$log"
    [[ $rc -eq 143 ]] || fail "exit $rc, expected 143"
    grep -q "second stop signal: exiting now" "$log" || fail "no message"
    [[ -f $work/a/report.json ]] && fail "a report was written"
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test $*"

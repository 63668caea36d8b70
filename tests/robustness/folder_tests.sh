#!/usr/bin/env bash
# folder_tests.sh TEST COLOC MPIEXEC PYTHON CASE WORKDIR — what a run may write and delete, and
# what it reads (issue 27; docs/robustness.md, "What is kept on disk", "Files a run reads"), on the
# tiny bed case, 1 and 2 ranks. Every refusal: exit 2, one message naming the key or file, no hang.
#
#   escape     output.checkpoint_file leaving the output folder: '../../victim.txt', an absolute
#              path, a subfolder that is a symbolic link to elsewhere; run and `coloc check`
#              refuse it, the file outside is untouched
#   ownnames   output.checkpoint_file named like the run's own files (series.csv, report.json,
#              fields_{step}.h5, the .xmf, snapshot.png, the failed state, the lock, a .tmp):
#              refused by run and by check; a good name still runs
#   cleanup    the clean-up at the start removes coloc's own unfinished .tmp files only: other
#              programs' *.tmp in output.dir and --out stay
#   lock       a second run into the folder of a running one (--out, or output.dir) is refused,
#              naming the first (pid); the first goes on and ends normally; after it, and after a
#              SIGKILLed run, the folder is free again (the lock is not stale)
#   restart    --restart of a file that the run would overwrite or remove in its own folder
#              (rebalance.tmp.h5, fields_NNNNNN.h5) is refused and the file kept; a restart in
#              place from its own checkpoint runs
#   mixed      runs never mix in one folder: a second run into a folder that holds another run's
#              files (report.json, fields_*.h5, the .xmf, the checkpoint) is refused on every
#              rank, naming them, and changes nothing; also through output.dir, and a --restart of
#              a checkpoint from elsewhere; --overwrite removes the earlier run's files first
#              (another program's file stays); --restart of the folder's own checkpoint continues
#   fifo       a FIFO as case file (run, check) or as --restart file: refused at once
#   deep       a case file with a 100,000-deep list (check, run) and a 50,000-deep --set value:
#              refused within seconds, naming the file and line / the key
set -u
test=$1 coloc=$2 mpiexec=$3 py=$4 case=$5 work=$6
shift 6
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# run NP OUT [args...]: coloc run CASE --out OUT on NP ranks, time-limited; output in $log,
# status in $rc
run() {
  local np=$1 out=$2
  shift 2
  log="$work/$(basename "$out").log"
  timeout 60 "$mpiexec" -n "$np" --bind-to none "$coloc" run "$case" --out "$out" --quiet \
    --set run.steps=2 "$@" > "$log" 2>&1
  rc=$?
  [[ $rc -eq 124 ]] && { cat "$log"; fail "timed out (hang): $*"; }
  return 0
}
# check [args...]: coloc check (one process), time-limited; output in $log, status in $rc
check() {
  log="$work/check.log"
  timeout 60 "$coloc" check "$@" > "$log" 2>&1
  rc=$?
  [[ $rc -eq 124 ]] && { cat "$log"; fail "timed out (hang): check $*"; }
  return 0
}
# refused TEXT: exit 2 and the error printed once, containing TEXT
refused() {
  local n
  [[ $rc -eq 2 ]] || { cat "$log"; fail "exit $rc, expected 2 with: $1"; }
  n=$(grep -c "^coloc: error:" "$log")
  [[ $n -eq 1 ]] || { cat "$log"; fail "the error was printed $n times (expected once)"; }
  grep -qF -- "$1" "$log" || { cat "$log"; fail "message does not contain: $1"; }
  grep "^coloc: error:" "$log"
}
ck=(--set output.checkpoint_interval=1)

case $test in
  escape)
    echo precious > "$work/victim.txt"
    mkdir -p "$work/o" "$work/elsewhere"
    run 2 "$work/o/a" "${ck[@]}" --set output.checkpoint_file=../../victim.txt
    refused "output.checkpoint_file: '../../victim.txt' leaves the run's output folder"
    run 2 "$work/o/a" "${ck[@]}" --set "output.checkpoint_file=$work/victim.txt"
    refused "output.checkpoint_file: '$work/victim.txt' is an absolute path"
    mkdir -p "$work/o/b" && ln -s "$work/elsewhere" "$work/o/b/sub"
    run 2 "$work/o/b" "${ck[@]}" --set output.checkpoint_file=sub/ck.h5
    refused "output.checkpoint_file: 'sub/ck.h5' leaves the run's output folder '$work/o/b' through a symbolic link"
    [[ $(cat "$work/victim.txt") == precious ]] || fail "the file outside the run was changed"
    [[ -z $(ls -A "$work/elsewhere") ]] || fail "the run wrote through the link: $(ls "$work/elsewhere")"
    for bad in ../../victim.txt "$work/victim.txt" a/../../x.h5; do
      check "$case" --set "output.checkpoint_file=$bad"
      refused "output.checkpoint_file: '$bad'"
    done
    ;;
  ownnames)
    for name in series.csv report.json 'fields_{step}.h5'; do
      run 1 "$work/a" "${ck[@]}" --set output.interval_steps=1 --set "output.checkpoint_file=$name"
      refused "output.checkpoint_file: '$name' is the name of the run's"
      [[ -e $work/a/$name ]] && fail "$name written"
    done
    for name in series.csv report.json 'fields_{step}.h5' particles_000002.h5 fields.xmf \
      particles.xmf snapshot.png checkpoint.failed.h5 .coloc.lock checkpoint.h5.tmp \
      rebalance.tmp.h5 sub/series.csv; do
      check "$case" --set "output.checkpoint_file=$name"
      refused "output.checkpoint_file: '$name' is the name of"
    done
    run 1 "$work/b" "${ck[@]}" --set output.interval_steps=1 --set 'output.checkpoint_file=ck_{step}.h5'
    [[ $rc -eq 0 ]] || { cat "$log"; fail "a good checkpoint name was refused"; }
    for f in ck_000001.h5 ck_000002.h5 series.csv report.json fields_000002.h5; do
      [[ -f $work/b/$f ]] || fail "no $f"
    done
    ;;
  cleanup)
    out=$work/a shared=$work/shared
    mkdir -p "$out" "$shared"
    foreign=("$shared/notes.tmp" "$shared/data.h5.tmp" "$shared/x.json.tmp" "$shared/y.csv.tmp"
             "$shared/z.xmf.tmp" "$out/editor.json.tmp" "$out/other.h5.tmp" "$out/fields_1.h5.tmp")
    own=("$out/series.csv.tmp" "$out/report.json.tmp" "$out/rebalance.tmp.h5"
         "$shared/fields_000002.h5.tmp" "$shared/particles_000004.h5.tmp" "$shared/fields.xmf.tmp"
         "$shared/ck_000004.h5.tmp" "$shared/ck_000004.failed.h5.tmp")
    for f in "${foreign[@]}" "${own[@]}"; do echo x > "$f"; done
    run 2 "$out" --set "output.dir=$shared" --set output.interval_steps=2 "${ck[@]}" \
      --set 'output.checkpoint_file=ck_{step}.h5'
    [[ $rc -eq 0 ]] || { cat "$log"; fail "run failed"; }
    for f in "${foreign[@]}"; do [[ -f $f ]] || fail "another program's file was deleted: $f"; done
    for f in "${own[@]}"; do [[ -e $f ]] && fail "coloc's stale file was kept: $f"; done
    [[ -f $shared/ck_000002.h5 && -f $out/series.csv ]] || fail "the run's files are missing"
    echo "kept: ${foreign[*]##*/}"
    ;;
  lock)
    out=$work/a
    # the first run: long, 1 rank, in the background
    "$mpiexec" -n 1 --bind-to none "$coloc" run "$case" --out "$out" --set run.steps=1000000 \
      > "$work/first.log" 2>&1 &
    mpi=$!
    rank=""
    for _ in $(seq 100); do
      sleep 0.2
      rank=$(pgrep -P "$mpi" | head -1)
      [[ -n $rank ]] && grep -q "^coloc: case" "$work/first.log" && break
    done
    grep -q "^coloc: case" "$work/first.log" || { kill "$mpi"; fail "the first run did not start"; }
    sleep 0.5
    run 2 "$out"
    refused "--out: the output folder '$out' is in use by another coloc run (pid $rank on host"
    run 2 "$work/b" --set "output.dir=$out"
    refused "output.dir: the output folder '$out' is in use by another coloc run (pid $rank"
    [[ -e $out/report.json ]] && fail "the second run wrote a report into the first one's folder"
    n1=$(wc -l < "$out/series.csv")
    sleep 0.5
    n2=$(wc -l < "$out/series.csv")
    [[ $n2 -gt $n1 ]] || fail "the first run's series.csv stopped growing ($n1, $n2)"
    kill -TERM "$rank"
    wait "$mpi"
    rc=$?
    tail -2 "$work/first.log"
    [[ $rc -eq 143 ]] || fail "the first run ended with $rc, expected 143 (SIGTERM)"
    "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(d['status']!='interrupted')" \
      "$out/report.json" || fail "the first run's report"
    # the lock goes with the run: the folder is free now, also after a run killed outright
    # (--overwrite: each later run replaces the one before in the folder, on purpose)
    run 2 "$out" --overwrite
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the folder is still locked after the first run"; }
    "$mpiexec" -n 1 --bind-to none "$coloc" run "$case" --out "$out" --set run.steps=1000000 \
      --overwrite > "$work/killed.log" 2>&1 &
    mpi=$!
    for _ in $(seq 100); do
      sleep 0.2
      rank=$(pgrep -P "$mpi" | head -1)
      [[ -n $rank ]] && grep -q "^coloc: case" "$work/killed.log" && break
    done
    kill -KILL "$rank"
    wait "$mpi"
    run 2 "$out" --overwrite
    [[ $rc -eq 0 ]] || { cat "$log"; fail "a SIGKILLed run left a stale lock"; }
    ;;
  restart)
    run 2 "$work/base" --set output.checkpoint_interval=2
    [[ $rc -eq 0 ]] || { cat "$log"; fail "base run failed"; }
    good=$work/base/checkpoint.h5
    mkdir -p "$work/b"
    cp "$good" "$work/b/rebalance.tmp.h5"
    run 2 "$work/b" --set run.steps=4 --restart "$work/b/rebalance.tmp.h5"
    refused "--restart: '$work/b/rebalance.tmp.h5' is the run's re-balancing scratch file"
    cmp -s "$good" "$work/b/rebalance.tmp.h5" || fail "the restart file was removed or changed"
    cp "$good" "$work/b/fields_000002.h5"
    run 2 "$work/b" --set run.steps=4 --set output.interval_steps=2 \
      --restart "$work/b/fields_000002.h5"
    refused "--restart: '$work/b/fields_000002.h5' is the run's output file of one step"
    cmp -s "$good" "$work/b/fields_000002.h5" || fail "the restart file was overwritten"
    # in place, from its own checkpoint: allowed (and continued)
    cp "$good" "$work/b/checkpoint.h5"
    run 2 "$work/b" --set run.steps=4 --set output.checkpoint_interval=2 \
      --restart "$work/b/checkpoint.h5"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "restart from the run's own checkpoint refused"; }
    ;;
  mixed)
    out=$work/a
    steps() {  # the steps report.json $1 says were run
      "$py" -c "import json,sys; print(json.load(open(sys.argv[1]))['run']['steps'])" "$1"
    }
    run 2 "$out" --set run.steps=4 --set output.interval_steps=2 "${ck[@]}"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the first run failed"; }
    echo "another program's" > "$out/notes.txt"
    run 2 "$out" --set run.steps=2
    refused "--out: the output folder '$out' holds the files of another run ("
    grep -qF "checkpoint.h5, fields.xmf, fields_000000.h5" "$log" || { cat "$log"; fail "files not named"; }
    [[ $(steps "$out/report.json") -eq 4 ]] || fail "the refused run changed report.json"
    [[ -f $out/fields_000004.h5 && -f $out/series.csv ]] || fail "the refused run removed files"
    # through output.dir, and a restart of a checkpoint from elsewhere into a used folder
    run 2 "$work/c" --set "output.dir=$out"
    refused "the output folders '$work/c' (--out) and '$out' (output.dir) hold the files of another run ($out/"
    cp "$out/checkpoint.h5" "$work/ck.h5"
    run 2 "$out" --set run.steps=6 --restart "$work/ck.h5"
    refused "holds the files of another run"
    # --overwrite: the earlier run's files go first, another program's stay
    run 2 "$out" --set run.steps=2 --set output.interval_steps=2 "${ck[@]}" --overwrite
    [[ $rc -eq 0 ]] || { cat "$log"; fail "--overwrite was refused"; }
    [[ $(steps "$out/report.json") -eq 2 ]] || fail "the report is not the new run's"
    for f in fields_000004.h5 particles_000004.h5; do
      [[ -e $out/$f ]] && fail "--overwrite kept the earlier run's $f"
    done
    grep -q "000004" "$out/fields.xmf" && fail "fields.xmf still lists the earlier run's step 4"
    [[ -f $out/notes.txt ]] || fail "--overwrite removed another program's file"
    # a restart of the folder's own checkpoint continues that run in it
    run 2 "$out" --set run.steps=4 --set output.interval_steps=2 "${ck[@]}" \
      --restart "$out/checkpoint.h5"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the restart in its own folder was refused"; }
    [[ $(steps "$out/report.json") -eq 4 && -f $out/fields_000004.h5 ]] ||
      fail "the restart did not continue to step 4"
    ;;
  fifo)
    mkfifo "$work/case.fifo" "$work/ck.fifo" || fail "mkfifo"
    log=$work/fifo.log
    timeout 60 "$mpiexec" -n 2 --bind-to none "$coloc" run "$work/case.fifo" --out "$work/a" \
      > "$log" 2>&1
    rc=$?
    refused "case file '$work/case.fifo' is a FIFO (named pipe), not a regular file"
    check "$work/case.fifo"
    refused "case file '$work/case.fifo' is a FIFO (named pipe), not a regular file"
    run 2 "$work/r" --restart "$work/ck.fifo"
    refused "--restart: '$work/ck.fifo' is a FIFO (named pipe), not a regular file"
    [[ -e $work/r ]] && fail "a refused --restart made the output folder"
    [[ -e $work/a ]] && fail "a refused case made the output folder"
    ;;
  deep)
    "$py" - "$work/deep.json" <<'PYEOF' || fail "writing the deep case"
import sys
n = 100000
open(sys.argv[1], "w").write('{"name": "deep",\n "description": ' + "[" * n + "]" * n + "}\n")
PYEOF
    t0=$SECONDS
    check "$work/deep.json"
    refused "$work/deep.json: lists and objects nested deeper than 64 levels at line 2, column 80"
    run 2 "$work/a" --set "description=$(printf '%*s' 50000 '' | tr ' ' '[')"
    refused "description: the --set value has lists and objects nested deeper than 64 levels"
    log=$work/deep_run.log
    timeout 60 "$mpiexec" -n 2 --bind-to none "$coloc" run "$work/deep.json" --out "$work/b" \
      > "$log" 2>&1
    rc=$?
    refused "$work/deep.json: lists and objects nested deeper than 64 levels"
    secs=$((SECONDS - t0))
    [[ $secs -le 20 ]] || fail "took $secs s"
    # 64 levels are fine (the key's own type check answers)
    check "$case" --set "description=$("$py" -c 'print("[" * 64 + "]" * 64)')"
    refused "description: expected a string"
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test"

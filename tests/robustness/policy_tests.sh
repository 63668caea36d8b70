#!/usr/bin/env bash
# policy_tests.sh TEST COLOC MPIEXEC PYTHON CASE WORKDIR — reliability, part three (issue 50;
# docs/robustness.md): one policy for every file coloc writes, restart files checked before any
# collective open, set-ups bounded by what they make, --overwrite that keeps the earlier run until
# the new one has started, checkpoint attributes checked like datasets, messages that name the key.
# On the tiny bed case, 1 and 2 ranks; every refusal: exit 2 (or 4 for a write), one message, no
# hang, nothing of another's changed.
#
#   draw       coloc check --draw PATH: a FIFO, a symbolic link (to a file outside), the case file
#              itself are refused and left as they were; an SVG of an earlier --draw is replaced;
#              no temporary is left
#   links      a symbolic link in --out where the run writes (log.txt) or `coloc plan` writes
#              (plan.csv) is refused, the file it points to untouched; a folder where
#              fields_000001.h5 goes fails the write (exit 4) and leaves no fields_000001.h5.tmp
#   names      every name coloc owns (log.txt, render_eps.png, plan.csv) and a second {step} are
#              refused as output.checkpoint_file by run and check; a 250-byte checkpoint name and
#              an --out path of ~3,900 bytes are refused by name (exit 2, not an abort in MPI-IO),
#              and the long --out is not made
#   overwrite  --overwrite with a set-up that fails (the particles do not fit) leaves the earlier
#              run's files as they were (report, output, log); a good --overwrite replaces them
#   restartfile  --restart of /proc/self/status (a regular file that reads differently on every
#              rank and reports size 0), of a text file and of an empty file: refused on every
#              rank within seconds, exit 2 (no hang in HDF5's collective open)
#   restartattrs  a checkpoint whose attributes are damaged (step -5, time NaN, config not JSON,
#              config 10,000 levels deep, a particle count of 1e12, /simulation steps -1): exit 2
#              naming the attribute ("damaged"), never out of memory
#   placement  random and layered sources of tiny particles set up in seconds (the work follows
#              the particles, not the sites): `coloc check` with radius 1e-5 m and 3e-6 m within
#              5 s (were 17 s and more than 25 s), a 2-rank run with 3e-6 m within 10 s; radius
#              1e-12 m is refused naming the source (no negative site count); a box of 1e16 m
#              places all 400 particles (were silently 0), a region of 1e16 m is refused by name
#   messages   bad values refused naming their key, in a short message: fluid.conductivity 1e300,
#              a wall at -7 K, an inflow gap of 1e300, a material conductivity of 1e300, a source
#              temperature of 1e300, a list index of 20 digits, a progress column given twice;
#              report.json of a run with heat off shows no fluid.conductivity (no sentinel);
#              `coloc snapshot DIR --step 999` names the step (no traceback); `coloc run | head
#              -1` ends with its report (no SIGPIPE death)
set -u
test=$1 coloc=$2 mpiexec=$3 py=$4 case=$5 work=$6
shift 6
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# run NP OUT [args...]: coloc run CASE --out OUT on NP ranks, time-limited; $log, $rc, $secs
run() {
  local np=$1 out=$2 t0=$SECONDS
  shift 2
  log="$work/run.log"
  timeout 60 "$mpiexec" -n "$np" --bind-to none "$coloc" run "$case" --out "$out" --quiet \
    --set run.steps=2 "$@" > "$log" 2>&1
  rc=$?
  secs=$((SECONDS - t0))
  [[ $rc -eq 124 ]] && { cat "$log"; fail "timed out (hang): $*"; }
  return 0
}
# check [args...]: coloc check (one process), time-limited; output in $log, status in $rc
check() {
  local t0=$SECONDS
  log="$work/check.log"
  timeout 60 "$coloc" check "$@" > "$log" 2>&1
  rc=$?
  secs=$((SECONDS - t0))
  [[ $rc -eq 124 ]] && { cat "$log"; fail "timed out (hang): check $*"; }
  return 0
}
# refused TEXT [STATUS]: exit STATUS (2) and the error printed once, containing TEXT
refused() {
  local n want=${2:-2}
  [[ $rc -eq $want ]] || { cat "$log"; fail "exit $rc, expected $want with: $1"; }
  n=$(grep -c "^coloc: error:" "$log")
  [[ $n -eq 1 ]] || { cat "$log"; fail "the error was printed $n times (expected once)"; }
  grep -qF -- "$1" "$log" || { cat "$log"; fail "message does not contain: $1"; }
  grep "^coloc: error:" "$log" | cut -c1-300
}
no_tmp() {  # no temporary of coloc's left in folder $1
  local left
  left=$(find "$1" -name '*.tmp' -o -name '*.tmp.*' 2>/dev/null)
  [[ -z $left ]] || fail "temporaries left: $left"
}

case $test in
  draw)
    check "$case" --draw "$work/layout.svg"
    [[ $rc -eq 0 && -f $work/layout.svg ]] || { cat "$log"; fail "a first --draw failed"; }
    check "$case" --draw "$work/layout.svg"
    [[ $rc -eq 0 ]] || { cat "$log"; fail "an SVG of an earlier --draw was not replaced"; }
    mkfifo "$work/fifo.svg" || fail mkfifo
    check "$case" --draw "$work/fifo.svg"
    refused "--draw: '$work/fifo.svg' is a FIFO (named pipe), not a regular file"
    [[ -p $work/fifo.svg ]] || fail "the FIFO was replaced"
    echo precious > "$work/victim.txt"
    ln -s "$work/victim.txt" "$work/link.svg"
    check "$case" --draw "$work/link.svg"
    refused "--draw: '$work/link.svg' is a symbolic link, not a regular file"
    [[ -L $work/link.svg && $(cat "$work/victim.txt") == precious ]] ||
      fail "the link or the file it points to was changed"
    cp "$case" "$work/case.json"
    check "$work/case.json" --draw "$work/case.json"
    refused "--draw: '$work/case.json' exists and is not a file of this kind"
    cmp -s "$case" "$work/case.json" || fail "the case file was overwritten"
    no_tmp "$work"
    ;;
  links)
    echo precious > "$work/victim.txt"
    mkdir -p "$work/a" && ln -s "$work/victim.txt" "$work/a/log.txt"
    run 2 "$work/a"
    refused "--out: '$work/a/log.txt' is a symbolic link, not a regular file"
    [[ $(cat "$work/victim.txt") == precious && -L $work/a/log.txt ]] || fail "written through the link"
    mkdir -p "$work/p" && ln -s "$work/victim.txt" "$work/p/plan.csv"
    log=$work/plan.log
    timeout 60 "$coloc" plan "$case" --ranks 2 --out "$work/p" > "$log" 2>&1
    rc=$?
    refused "'$work/p/plan.csv' is a symbolic link, not a regular file"
    [[ $(cat "$work/victim.txt") == precious ]] || fail "coloc plan wrote through the link"
    mkdir -p "$work/b/fields_000001.h5"
    run 2 "$work/b" --set output.interval_steps=1
    refused "'$work/b/fields_000001.h5' is a directory, not a regular file" 4
    [[ -d $work/b/fields_000001.h5 && -f $work/b/fields_000000.h5 ]] || fail "the folder was replaced"
    no_tmp "$work/b"
    ;;
  names)
    for name in log.txt render_eps.png plan.csv plan.json; do
      check "$case" --set "output.checkpoint_file=$name"
      refused "output.checkpoint_file: '$name' is the name of"
    done
    run 1 "$work/a" --set output.checkpoint_interval=1 --set output.checkpoint_file=log.txt
    refused "output.checkpoint_file: 'log.txt' is the name of the run's log (log.txt)"
    check "$case" --set 'output.checkpoint_file=ck_{step}_{step}.h5'
    refused "output.checkpoint_file: 'ck_{step}_{step}.h5' has {step} twice"
    long=$(printf 'c%.0s' $(seq 250)).h5
    check "$case" --set "output.checkpoint_file=$long"
    refused "output.checkpoint_file: '$long' is a name of 253 bytes"
    run 2 "$work/b" --set output.checkpoint_interval=1 --set "output.checkpoint_file=$long"
    refused "output.checkpoint_file: '$long' is a name of 253 bytes"
    deep=$work
    while [[ ${#deep} -lt 3900 ]]; do deep=$deep/$(printf 'd%.0s' $(seq 190)); done
    run 2 "$deep"
    refused "bytes from the root: coloc writes paths of at most 1024 bytes"
    [[ -z $(ls -A "$work" | grep -v '\.log$') ]] || fail "something was made: $(ls -A "$work")"
    ;;
  overwrite)
    out=$work/a
    run 2 "$out" --set output.interval_steps=1
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the first run failed"; }
    cp "$out/report.json" "$work/report.before" && cp "$out/log.txt" "$work/log.before"
    run 2 "$out" --overwrite --set particles.sources.0.count=100000
    refused "particles.sources[0].count: 100000 particles do not fit"
    grep -qF "the earlier run's files in '$out' are left as they were" "$log" || { cat "$log"; fail "not said"; }
    cmp -s "$out/report.json" "$work/report.before" || fail "the earlier report was replaced"
    cmp -s "$out/log.txt" "$work/log.before" || fail "the earlier log was changed"
    for f in fields_000002.h5 particles_000002.h5 fields.xmf series.csv; do
      [[ -f $out/$f ]] || fail "--overwrite removed $f before the new run had started"
    done
    run 2 "$out" --overwrite --set run.steps=1 --set output.interval_steps=1
    [[ $rc -eq 0 ]] || { cat "$log"; fail "a good --overwrite failed"; }
    [[ -e $out/fields_000002.h5 ]] && fail "the earlier run's fields_000002.h5 was kept"
    "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(d['run']['steps'] != 1)" \
      "$out/report.json" || fail "the report is not the new run's"
    ;;
  restartfile)
    echo "not a checkpoint" > "$work/text.h5"
    : > "$work/empty.h5"
    run 2 "$work/p" --restart /proc/self/status
    refused "checkpoint '/proc/self/status': /proc/self/status: cannot open: the file is empty"
    [[ $secs -le 20 ]] || fail "took $secs s"
    run 2 "$work/t" --restart "$work/text.h5"
    refused "text.h5: cannot open: not an HDF5 file (no HDF5 signature)"
    run 2 "$work/e" --restart "$work/empty.h5"
    refused "empty.h5: cannot open: the file is empty"
    ;;
  restartattrs)
    run 2 "$work/a" --set output.checkpoint_interval=2
    [[ $rc -eq 0 ]] || { cat "$log"; fail "base run failed"; }
    good=$work/a/checkpoint.h5
    n=0
    damage() {  # damage EXPECTED OBJECT NAME EXPR
      n=$((n + 1))
      "$py" "$here/damage_checkpoint.py" "$good" "$work/bad.h5" attr "$2" "$3" "$4" ||
        fail "damaging $2 $3"
      run 2 "$work/x$n" --set run.steps=4 --restart "$work/bad.h5"
      refused "$1"
    }
    damage "damaged: attribute step = -5" / step "np.int64(-5)"
    damage "damaged: attribute time = nan" / time "np.float64('nan')"
    damage "damaged: attribute config is not the JSON of a case" / config "np.bytes_(b'{\"fluid\": ')"
    damage "damaged: attribute config is not the JSON of a case" / config \
      "np.bytes_(b'[' * 10000 + b']' * 10000)"
    damage "is damaged: /particles: attribute count = 1000000000000, but /particles/id holds 400 rows" \
      /particles count "np.int64(10**12)"
    damage "is damaged: /simulation: a time of" /simulation steps "np.int64(-1)"
    ;;
  placement)
    # particles.dt small enough for the tiny particles (the DEM's own check), 1 DEM step a CFD step
    tiny=(--set particles.dt=1e-8 --set coupling.dem_substeps=1)
    for type in random layered; do
      for r in 1e-5 3e-6; do
        check "$case" "${tiny[@]}" --set "particles.sources.0.type=$type" \
          --set "particles.sources.0.radius=$r"
        [[ $rc -eq 0 ]] || { cat "$log"; fail "$type, radius $r: exit $rc"; }
        [[ $secs -le 5 ]] || fail "$type, radius $r: coloc check took $secs s"
        echo "coloc check, $type source, radius $r: $secs s"
      done
      run 2 "$work/$type" "${tiny[@]}" --set run.steps=1 --set "particles.sources.0.type=$type" \
        --set particles.sources.0.radius=3e-6
      [[ $rc -eq 0 ]] || { cat "$log"; fail "$type, radius 3e-6: the run failed"; }
      [[ $secs -le 10 ]] || fail "$type, radius 3e-6: the run took $secs s"
      "$py" -c "import json,sys; sys.exit(json.load(open(sys.argv[1]))['particles']['count'] != 400)" \
        "$work/$type/report.json" || fail "$type, radius 3e-6: not 400 particles"
      echo "coloc run, $type source, radius 3e-6, 2 ranks: $secs s, 400 particles"
    done
    check "$case" --set particles.sources.0.radius=1e-12
    refused "particles.sources[0]: the region holds more than"
    grep -q -- "-[0-9]* sites" "$log" && fail "a negative site count"
    # a box of 1e16 m: the particles are all placed (they were silently lost), and a region of
    # 1e16 m of millimetre sites is refused by name (its site count overflowed)
    run 2 "$work/big" --set 'domain.length=[1e16,1e16,4e16]'
    [[ $rc -eq 0 ]] || { cat "$log"; fail "a box of 1e16 m failed"; }
    "$py" -c "import json,sys; sys.exit(json.load(open(sys.argv[1]))['particles']['count'] != 400)" \
      "$work/big/report.json" || fail "a box of 1e16 m ran with fewer particles than asked"
    run 1 "$work/big2" --set 'domain.length=[1e16,1e16,4e16]' \
      --set 'particles.sources.0.hi=[1e16,1e16,1.4e16]'
    refused "particles.sources[0]: the region holds more than 4.61e+18 particle sites"
    ;;
  messages)
    check "$case" --set fluid.heat=true --set fluid.conductivity=1e300 \
      --set fluid.heat_capacity=4186 --set fluid.initial_temperature=300
    refused "fluid.conductivity: value 1e+300 is out of range"
    check "$case" --set 'fluid.boundary.xlo={"type":"wall","temperature":-7}'
    refused "fluid.boundary.xlo.temperature: value -7 is out of range"
    check "$case" --set 'particles.inflow=[{"face":"zlo","rate":10,"radius":0.0005,"gap":1e300}]' \
      --set particles.boundary.zhi=outflow
    refused "particles.inflow[0]"
    [[ $(grep "^coloc: error:" "$log" | wc -c) -lt 400 ]] || fail "a long message: $(cat "$log")"
    check "$case" --set particles.materials.0.conductivity=1e300
    refused "particles.materials[0].conductivity: value 1e+300 is out of range"
    check "$case" --set particles.sources.0.temperature=1e300
    refused "particles.sources[0].temperature: value 1e+300 is out of range"
    check "$case" --set particles.sources.99999999999999999999.count=1
    refused "particles.sources.99999999999999999999.count: list index 99999999999999999999 is out of range"
    check "$case" --set run.progress_columns=step,time,step
    refused "run.progress_columns: 'step' is given twice"
    check "$case" --set particles.heat=true --set particles.materials.0.heat_capacity=840 \
      --set particles.materials.0.conductivity=1 --set particles.wall_temperature=0
    refused "particles.wall_temperature: value 0 is out of range"
    run 1 "$work/off" --set output.interval_steps=1
    [[ $rc -eq 0 ]] || { cat "$log"; fail "the bed run failed"; }
    log=$work/snap.log
    timeout 60 "$coloc" snapshot "$work/off" --step 999 > "$log" 2>&1
    rc=$?
    [[ $rc -ne 0 ]] || fail "coloc snapshot --step 999 exited 0"
    grep -q "Traceback" "$log" && { cat "$log"; fail "a Python traceback"; }
    grep -qF "no output at step 999 in '$work/off'" "$log" ||
      { cat "$log"; fail "the missing step not named"; }
    # the terminal goes away (a pipe closed after one line): the run still ends with its report
    timeout 60 "$coloc" run "$case" --out "$work/pipe" --set run.steps=3 2>/dev/null | head -1
    rc=${PIPESTATUS[0]}
    [[ $rc -eq 0 && -f $work/pipe/report.json ]] || fail "coloc run | head -1: exit $rc, report missing"
    "$py" - "$work/off/report.json" <<'PYEOF' || fail "a sentinel in report.json"
import json, sys
c = json.load(open(sys.argv[1]))["config"]
bad = [k for k in ("conductivity", "heat_capacity", "initial_temperature") if k in c["fluid"]]
bad += [k for k in ("heat_capacity", "conductivity") if k in c["particles"]["materials"][0]]
bad += ["wall_temperature"] if "wall_temperature" in c["particles"] else []
bad += ["boundary.zlo.temperature"] if "temperature" in c["fluid"]["boundary"]["zlo"] else []
print("keys not given and not shown:", "none shown" if not bad else bad)
sys.exit(1 if bad else 0)
PYEOF
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test"

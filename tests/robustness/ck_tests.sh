#!/usr/bin/env bash
# ck_tests.sh TEST COLOC MPIEXEC PYTHON CASE WORKDIR — checkpoint/restart and blow-up tests of the
# `coloc` driver on the tiny fluidised bed tests/robustness/cases/bed.json (docs/output.md).
#
#   readback       a checkpoint read back with h5py equals the run's regular output of that step
#   identity NP    N+M steps with checkpoints vs a restart from step N on NP ranks: the final
#                  checkpoints and the series.csv rows are identical, the report's physics equal
#   interval NP S  strategy S on NP ranks, 12 steps with a checkpoint at the end only and with
#                  one at every step: the final checkpoints identical, and so are those of
#                  restarts from steps 5 and 9 (writing a checkpoint does not change the run)
#   ranks          1 rank to step 12; restart on 2 ranks from step 4; on 4 ranks from step 8:
#                  final states equal to 1e-10 (relative)
#   kill           a run SIGKILLed while writing a checkpoint (after the data, before the rename)
#                  keeps the previous checkpoint, which restarts and ends as the uninterrupted run
#   blowup E K=V   a restart made unstable by K=V (an inlet far too fast, a tiny overlap limit):
#                  message E, exit 3 on every rank, no hang, a readable checkpoint marked failed,
#                  the last good one kept, and a restart from the failed one refused
#   badrestart     --restart with a missing, a corrupt, another grid's and a failed checkpoint:
#                  a clear error, non-zero exit, no hang
#   damaged        --restart from a checkpoint with one flipped bit in the ids, masses, positions,
#                  contact holders or the fluid pressure (Fletcher32 checksum), or rewritten with
#                  valid checksums but impossible values (a duplicate id, a negative mass, a
#                  particle outside the box, a contact held by no particle, a NaN pressure):
#                  refused naming the file and dataset, exit 2 on every rank, no hang
#   check          `coloc check --ranks 2` (one process) shows the blocks, the particles a rank
#                  and the modelled imbalance that a 2-rank run then reports, for the uniform and
#                  the balanced strategy; exit 2 for a bad case and for a case too large for the
#                  machine (run refused the same way); `coloc keys PREFIX`
#   draw NP S      `coloc check --ranks NP --draw` with strategy S: an SVG whose four panels each
#                  tile the drawn plane with NP ranks' blocks, and whose panel S shows the boxes
#                  (and, independent, the particle boxes) a NP-rank run of S reports, cut by the
#                  plane; a file that cannot be written is an error naming it
#   drawplane      a 1 x 2 x 1 grid (cut along y) drawn on the default plane (x-z, the cut along y
#                  not in it: one rank), then with --plane yz (both ranks, split along y) and
#                  --plane xy (both, across x, up y); --plane without --draw and a bad plane:
#                  exit 2 naming --plane
set -u
test=$1 coloc=$2 mpiexec=$3 py=$4 case=$5 work=$6
shift 6
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cmp="$py $here/compare_checkpoints.py"
expect="$here/../common/expect_error.sh"
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# run NP OUT [args...]: coloc run CASE on NP ranks (time-limited: a hang fails)
run() {
  local np=$1 out=$2
  shift 2
  timeout 120 "$mpiexec" -n "$np" --bind-to none "$coloc" run "$case" --out "$out" --quiet "$@" \
    > "$out.log" 2>&1
  local rc=$?
  [[ $rc -eq 124 ]] && { cat "$out.log"; fail "timed out (hang): $*"; }
  return $rc
}
# series rows of steps > $3 of file $1 equal those of file $2 (after the header)
same_series_tail() {
  local n
  n=$(($(wc -l < "$2") - 1))
  diff <(tail -n "$n" "$1") <(tail -n "$n" "$2") > /dev/null || fail "series.csv rows differ: $1 $2"
  [[ $(head -1 "$1") == $(head -1 "$2") ]] || fail "series.csv headers differ"
}
# the report's physics (not timings) equal
same_report() {
  "$py" - "$1" "$2" <<'EOF' || fail "reports differ: $1 $2"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
keys = [("run", "steps"), ("run", "dem_substeps"), ("run", "sim_time"), ("checks", "momentum_balance"),
        ("checks", "mass_balance"), ("pressure", "iterations_avg"), ("pressure", "iterations_max"),
        ("pressure", "iterations_last"), ("fluid", "time"), ("fluid", "dt_last"),
        ("fluid", "steady_residual"), ("fluid", "drag_force"), ("coupling", "solid_volume"),
        ("particles", "count")]
bad = [k for k in keys if a[k[0]][k[1]] != b[k[0]][k[1]]]
for k in bad: print("report", ".".join(k), a[k[0]][k[1]], "vs", b[k[0]][k[1]])
sys.exit(1 if bad else 0)
EOF
}

case $test in
  readback)
    run 2 "$work/a" --set run.steps=6 --set output.interval_steps=3 --set output.checkpoint_interval=3 \
      --set output.checkpoint_file=ck_{step}.h5 || { cat "$work/a.log"; fail "run failed"; }
    for s in 000003 000006; do
      "$py" "$here/check_checkpoint.py" "$work/a/ck_$s.h5" "$work/a/fields_$s.h5" \
        "$work/a/particles_$s.h5" || fail "checkpoint $s"
    done
    ;;
  identity)
    np=$1
    common=(--set run.steps=10 --set output.checkpoint_interval=5 --set output.checkpoint_file=ck_{step}.h5)
    run "$np" "$work/a" "${common[@]}" || { cat "$work/a.log"; fail "run a failed"; }
    run "$np" "$work/b" "${common[@]}" --restart "$work/a/ck_000005.h5" ||
      { cat "$work/b.log"; fail "restart failed"; }
    [[ -f $work/b/ck_000005.h5 ]] && fail "the restart rewrote the step-5 checkpoint"
    $cmp "$work/a/ck_000010.h5" "$work/b/ck_000010.h5" || fail "final checkpoints differ"
    same_series_tail "$work/a/series.csv" "$work/b/series.csv"
    [[ $(wc -l < "$work/b/series.csv") -eq 6 ]] || fail "restart series should hold steps 6-10"
    # the closing line counts the steps this run made (5), not the total (10)
    grep -q "^coloc: 10 steps (" "$work/a.log" || { cat "$work/a.log"; fail "run a's step count"; }
    grep -q "^coloc: 5 steps ([0-9]* DEM sub-steps), steps 6-10 after the restart" "$work/b.log" ||
      { cat "$work/b.log"; fail "the restart's closing line does not count its own 5 steps"; }
    same_report "$work/a/report.json" "$work/b/report.json"
    ;;
  interval)
    # interval NP STRATEGY: the same 12 steps with a checkpoint at the end only, and with one at
    # every step: the final checkpoints identical (writing checkpoints does not change the run);
    # restarts from steps 5 and 9 of the second end identical too
    np=$1 strategy=$2
    common=(--set run.steps=12 --set partition.strategy="$strategy")
    run "$np" "$work/a" "${common[@]}" --set output.checkpoint_interval=12 ||
      { cat "$work/a.log"; fail "run a failed"; }
    run "$np" "$work/b" "${common[@]}" --set output.checkpoint_interval=1 \
      --set output.checkpoint_file=ck_{step}.h5 || { cat "$work/b.log"; fail "run b failed"; }
    $cmp "$work/a/checkpoint.h5" "$work/b/ck_000012.h5" ||
      fail "checkpoints at every step changed the run"
    for s in 5 9; do
      run "$np" "$work/r$s" "${common[@]}" --set output.checkpoint_interval=12 \
        --restart "$work/b/ck_00000$s.h5" || { cat "$work/r$s.log"; fail "restart $s failed"; }
      $cmp "$work/a/checkpoint.h5" "$work/r$s/checkpoint.h5" ||
        fail "the restart from step $s differs from the run without checkpoints"
    done
    same_report "$work/a/report.json" "$work/b/report.json"
    ;;
  ranks)
    common=(--set run.steps=12 --set output.checkpoint_interval=4 --set output.checkpoint_file=ck_{step}.h5)
    run 1 "$work/a" "${common[@]}" || { cat "$work/a.log"; fail "run a (1 rank) failed"; }
    run 2 "$work/b" "${common[@]}" --restart "$work/a/ck_000004.h5" ||
      { cat "$work/b.log"; fail "restart on 2 ranks failed"; }
    run 4 "$work/c" "${common[@]}" --restart "$work/b/ck_000008.h5" ||
      { cat "$work/c.log"; fail "restart on 4 ranks failed"; }
    $cmp "$work/a/ck_000008.h5" "$work/b/ck_000008.h5" --rtol 1e-10 || fail "1 vs 2 ranks, step 8"
    $cmp "$work/a/ck_000012.h5" "$work/b/ck_000012.h5" --rtol 1e-10 || fail "1 vs 2 ranks"
    $cmp "$work/a/ck_000012.h5" "$work/c/ck_000012.h5" --rtol 1e-10 || fail "1 vs 2 vs 4 ranks"
    ;;
  kill)
    common=(--set run.steps=8 --set output.checkpoint_interval=2)
    run 2 "$work/full" "${common[@]}" || { cat "$work/full.log"; fail "uninterrupted run failed"; }
    # the test build of the driver (COLOC_FAULTS: coloc_faults) has the kill hook
    (export COLOC_TEST_KILL_IN_CHECKPOINT=6; coloc=${COLOC_FAULTS:?}; run 2 "$work/k" "${common[@]}") &&
      fail "the killed run exited 0"
    [[ -f $work/k/checkpoint.h5 ]] || fail "no checkpoint left by the killed run"
    [[ -f $work/k/checkpoint.h5.tmp ]] || echo "note: no checkpoint.h5.tmp left (killed early)"
    "$py" -c "import h5py,sys; f=h5py.File(sys.argv[1]); assert f.attrs['step']==4, f.attrs['step']" \
      "$work/k/checkpoint.h5" || fail "the surviving checkpoint is not that of step 4"
    run 2 "$work/k" "${common[@]}" --restart "$work/k/checkpoint.h5" ||
      { cat "$work/k.log"; fail "restart from the surviving checkpoint failed"; }
    $cmp "$work/full/checkpoint.h5" "$work/k/checkpoint.h5" || fail "restarted run differs"
    ;;
  blowup)
    # blowup EXPECTED KEY=VALUE: 3 good steps with checkpoints, then a restart with KEY=VALUE
    # that makes step 4 fail on some rank (the others learn it collectively), e.g. an inlet 100
    # times too fast (fluid CFL check) or a tiny particles.overlap_limit (DEM check).
    expected=$1 breaker=$2
    run 2 "$work/u" --set run.steps=3 --set output.checkpoint_interval=1 ||
      { cat "$work/u.log"; fail "run failed"; }
    "$expect" "$expected" -- "$mpiexec" -n 2 --bind-to none "$coloc" \
      run "$case" --out "$work/u" --quiet --restart "$work/u/checkpoint.h5" \
      --set run.steps=10 --set output.checkpoint_interval=1 --set "$breaker" \
      > "$work/u2.log" 2>&1
    rc=$?
    cat "$work/u2.log"
    [[ $rc -eq 0 ]] || fail "expected the blow-up message"
    grep -q "the run failed in step 4 " "$work/u2.log" || fail "no step in the message"
    failed=$work/u/checkpoint.failed.h5
    [[ -f $failed ]] || fail "no failed checkpoint"
    "$py" - "$failed" "$work/u/checkpoint.h5" "$expected" <<'EOF' || fail "checkpoints after the failure"
import h5py, sys
f = h5py.File(sys.argv[1], "r")
st = f.attrs["status"].decode()
print("status:", st)
assert st.startswith("failed: the run failed in step 4"), st
assert sys.argv[3] in st, st
assert f["fluid/p"].shape == (16, 4, 4) and f["particles"].attrs["count"] == 400
g = h5py.File(sys.argv[2], "r")
assert g.attrs["status"].decode() == "ok" and g.attrs["step"] == 3, "last good checkpoint lost"
EOF
    "$expect" "its status is 'failed" -- "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" \
      --out "$work/r" --quiet --restart "$failed" || fail "restart from a failed checkpoint"
    ;;
  badrestart)
    run 2 "$work/a" --set run.steps=2 --set output.checkpoint_interval=2 ||
      { cat "$work/a.log"; fail "run failed"; }
    echo "not an HDF5 file" > "$work/corrupt.h5"
    head -c 3000 "$work/a/checkpoint.h5" > "$work/truncated.h5"
    # each refusal in a folder of its own (a refused run leaves its report.json)
    i=0
    for t in "no such file|$work/missing.h5" "cannot open|$work/corrupt.h5" \
             "checkpoint '$work/truncated.h5'|$work/truncated.h5"; do
      i=$((i + 1))
      "$expect" "${t%%|*}" -- "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" --out \
        "$work/x$i" --quiet --restart "${t#*|}" || fail "--restart ${t#*|}"
    done
    "$expect" "its grid has 4x4x16 cells, the case 4x4x20" -- "$mpiexec" -n 2 --bind-to none \
      "$coloc" run "$case" --out "$work/grid" --quiet --set "domain.cells=[4,4,20]" \
      --restart "$work/a/checkpoint.h5" || fail "restart on another grid"
    "$expect" "it was written in run.mode coupled" -- "$mpiexec" -n 2 --bind-to none \
      "$coloc" run "$case" --out "$work/mode" --quiet --set run.mode=fluid \
      --restart "$work/a/checkpoint.h5" || fail "restart in another mode"
    ;;
  damaged)
    run 2 "$work/a" --set run.steps=4 --set output.checkpoint_interval=4 ||
      { cat "$work/a.log"; fail "run failed"; }
    good=$work/a/checkpoint.h5
    n=0
    damage() {  # damage EXPECTED MODE DATASET ARG (each refusal in a folder of its own)
      local bad=$work/bad.h5
      n=$((n + 1))
      "$py" "$here/damage_checkpoint.py" "$good" "$bad" "$2" "$3" "$4" || fail "damaging $3"
      "$expect" "$1" -- "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" \
        --out "$work/x$n" --quiet --restart "$bad" > "$work/damaged.log" 2>&1
      local rc=$?
      cat "$work/damaged.log"
      [[ $rc -eq 0 ]] || fail "damaged $3 ($2) not refused as expected"
      grep -q "^PASS: exit 2 with" "$work/damaged.log" ||
        fail "damaged $3: exit status is not 2"
    }
    for ds in particles/id particles/mass particles/x particles/contacts/holder fluid/p; do
      damage "$work/bad.h5:/$ds: H5Dread failed" flip "$ds" 13
      damage "Fletcher32 checksum" flip "$ds" 3
    done
    damage "is damaged: /particles/id: id" set particles/id "a[3] = a[4]"
    damage "is damaged: /particles/id: particle id -" set particles/id "a[7] = -5"
    damage "/particles/mass: particle id" set particles/mass "a[5] = -3.7e8"
    damage "/particles/radius: particle id" set particles/radius "a[2] = np.nan"
    damage "/particles/x: particle id" set particles/x "a[9, 2] = 1.0"
    damage "/particles/contacts/holder: row 0" set particles/contacts/holder "a[0] = 99999"
    damage "/fluid/p: value nan" set fluid/p "a[1, 2, 3] = np.nan"
    damage "/fluid/eps: value" set fluid/eps "a[0, 0, 0] = -0.5"
    ;;
  check)
    for st in uniform balanced; do
      timeout 60 "$coloc" check "$case" --ranks 2 --set partition.strategy=$st > "$work/check_$st.txt" 2>&1 ||
        { cat "$work/check_$st.txt"; fail "coloc check ($st) exit $?"; }
      cat "$work/check_$st.txt"
      grep -q "the case is valid for 2 rank(s); nothing was run" "$work/check_$st.txt" || fail "no verdict"
      [[ -e $work/c_$st ]] && fail "coloc check wrote output"
      run 2 "$work/r_$st" --set run.steps=1 --set partition.strategy=$st ||
        { cat "$work/r_$st.log"; fail "run ($st) failed"; }
      "$py" - "$work/check_$st.txt" "$work/r_$st/report.json" "$st" <<'EOF2' || fail "check and run differ ($st)"
import json, re, sys
text, rep, st = open(sys.argv[1]).read(), json.load(open(sys.argv[2])), sys.argv[3]
m = re.search(r"^\* " + st + r" +(\d+)x(\d+)x(\d+) +(\d+)x(\d+)x(\d+) .* ([0-9.]+) +[0-9.]+ MiB$", text, re.M)
assert m, "no line for " + st
dims = [int(m.group(i)) for i in (1, 2, 3)]
print("check:", dims, m.group(7), " run:", rep["partition"]["fluid_dims"], rep["partition"].get("balanced"))
assert dims == rep["partition"]["fluid_dims"], (dims, rep["partition"])
if st == "balanced":
    assert abs(float(m.group(7)) - rep["partition"]["balanced"]["modelled_imbalance"]) < 1e-3
    assert abs(float(re.search(r"^  uniform .* ([0-9.]+) +[0-9.]+ MiB$", text, re.M).group(1)) -
               rep["partition"]["balanced"]["uniform_modelled_imbalance"]) < 1e-3
EOF2
    done
    # coloc check and coloc plan model the same imbalance for every strategy (independent too:
    # fluid cells on the fluid's blocks, particles on their own boxes)
    timeout 60 "$coloc" check "$case" --ranks 4 > "$work/check4.txt" 2>&1 || { cat "$work/check4.txt"; fail "check 4"; }
    timeout 60 "$coloc" plan "$case" --ranks 4 --strategy uniform balanced independent tiled \
      --out "$work/plan4" > "$work/plan4.txt" 2>&1 || { cat "$work/plan4.txt"; fail "plan 4"; }
    "$py" - "$work/check4.txt" "$work/plan4.txt" <<'EOF2' || fail "check and plan model different imbalances"
import re, sys
check, plan = open(sys.argv[1]).read(), open(sys.argv[2]).read()
n = 0
for st in ("uniform", "balanced", "independent", "tiled"):
    c = re.search(r"^[* ] " + st + r" .* ([0-9.]+) +[0-9.]+ [KMG]iB$", check, re.M)
    p = re.search(r"^" + st + r" +4 +\S+ +\S+ +([0-9.]+) ", plan, re.M)
    if not p:
        continue
    assert c, "no check line for " + st
    print(st, "check", c.group(1), "plan", p.group(1))
    assert abs(float(c.group(1)) - float(p.group(1))) < 2e-3, st
    n += 1
assert n >= 3, n
EOF2
    "$expect" "an inlet but no outlet" -- "$coloc" check "$case" --ranks 2 \
      --set 'fluid.boundary.zhi={"type":"wall"}' || fail "check of a bad case"
    # a CFL the run stops at in its first step: check refuses the case (and the run does stop);
    # one the inlet alone keeps below fluid.cfl_max stays valid (and runs)
    fast="fluid.boundary.zlo.velocity=[0,0,5]"
    "$expect" "fluid.dt: the CFL of the first step would be at least 2 " -- "$coloc" check "$case" \
      --ranks 2 --set "$fast" || fail "check of a case whose CFL stops the run"
    "$expect" "the run failed in step 1 " -- "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" \
      --out "$work/cfl" --quiet --set run.steps=2 --set "$fast" || fail "the fast inlet did not stop the run"
    grep -q "exceeds fluid.cfl_max" "$work/cfl/report.json" || fail "the run did not stop for its CFL"
    slow="fluid.boundary.zlo.velocity=[0,0,1]"
    timeout 60 "$coloc" check "$case" --ranks 2 --set "$slow" > "$work/check_slow.txt" 2>&1 ||
      { cat "$work/check_slow.txt"; fail "check refused an inlet below fluid.cfl_max"; }
    grep -q "CFL 1.33, at least 0.4 (fluid.cfl_max = 1)" "$work/check_slow.txt" ||
      { cat "$work/check_slow.txt"; fail "no CFL range"; }
    run 2 "$work/slow" --set run.steps=2 --set "$slow" || { cat "$work/slow.log"; fail "the slow inlet's run failed"; }
    "$expect" "a run on 2 rank(s) here would be refused" -- "$coloc" check "$case" --ranks 2 \
      --set 'domain.cells=[4000,4000,4000]' || fail "check of a case too large"
    "$expect" "no case-file key starts with this" -- "$coloc" keys particles.nope || fail "keys"
    "$coloc" keys particles.sources > "$work/keys.txt" || fail "keys particles.sources"
    grep -q "particles.sources{type=random}.count" "$work/keys.txt" || fail "keys: no count"
    grep -q "fluid.nu" "$work/keys.txt" && fail "keys particles.sources lists fluid keys"
    ;;
  draw)
    np=$1 st=$2
    timeout 60 "$coloc" check "$case" --ranks "$np" --set partition.strategy=$st \
      --draw "$work/layouts.svg" > "$work/check.txt" 2>&1 || { cat "$work/check.txt"; fail "coloc check --draw"; }
    grep -q "drew the layouts in $work/layouts.svg" "$work/check.txt" || fail "no line naming the picture"
    [[ -e $work/layouts.svg.tmp ]] && fail "a temporary file left"
    run "$np" "$work/r" --set run.steps=1 --set partition.strategy=$st || { cat "$work/r.log"; fail "run failed"; }
    "$py" - "$work/layouts.svg" "$work/r/report.json" "$np" "$st" <<'EOF2' || fail "the picture is not the run's layout"
import json, sys
import xml.etree.ElementTree as ET
svg, rep, np_, st = ET.parse(sys.argv[1]).getroot(), json.load(open(sys.argv[2])), int(sys.argv[3]), sys.argv[4]
ns = {"s": "http://www.w3.org/2000/svg"}
cells = rep["config"]["domain"]["cells"]
up, across, normal = 2, 0, 1  # gravity -z; x and y equal: the first of the others across
mid = cells[normal] // 2
panels = {g.get("data-strategy"): g for g in svg.iter("{http://www.w3.org/2000/svg}g") if g.get("class") == "panel"}
assert sorted(panels) == ["balanced", "independent", "tiled", "uniform"], sorted(panels)
def rects(g, cls):
    out = []
    for r in g.findall("s:rect", ns):
        if r.get("class") == cls:
            lo = [int(v) for v in r.get("data-lo", "0 0").split()] if r.get("data-lo") else None
            hi = [int(v) for v in r.get("data-hi").split()] if r.get("data-hi") else None
            out.append((int(r.get("data-rank")), lo, hi))
    return out
for name, g in panels.items():
    assert int(g.get("data-ranks")) == np_, (name, g.get("data-ranks"))
    blocks = rects(g, "block")
    area = sum((h[0] - l[0]) * (h[1] - l[1]) for _, l, h in blocks)
    assert area == cells[across] * cells[up], (name, area, blocks)
    for a in range(len(blocks)):
        for b in range(a + 1, len(blocks)):
            (_, l1, h1), (_, l2, h2) = blocks[a], blocks[b]
            assert not (l1[0] < h2[0] and l2[0] < h1[0] and l1[1] < h2[1] and l2[1] < h1[1]), (name, blocks[a], blocks[b])
    assert len({r for r, _, _ in blocks}) == len(blocks), (name, "a rank drawn twice")
# The run's own boxes, cut by the plane, are what panel st shows.
def cut(boxes):
    return sorted((r, [b[across], b[up]], [b[3 + across], b[3 + up]])
                  for r, b in enumerate(boxes) if b[normal] <= mid < b[3 + normal])
part = rep["partition"]
drawn = sorted(rects(panels[st], "block"))
print("drawn:", drawn)
assert drawn == cut(part["boxes"]), (drawn, cut(part["boxes"]))
if st == "independent":
    dem = sorted((r, None, None) for r, _, _ in cut(part["particle_boxes"])
                 if part["particle_boxes"][r] != part["boxes"][r])
    assert sorted(rects(panels[st], "dem-block")) == dem, (rects(panels[st], "dem-block"), dem)
    assert dem, "no particle box of its own drawn"
print("the picture holds the run's layout:", st, np_)
EOF2
    "$expect" "cannot create '$work/no/such/dir/x.svg.tmp'" -- "$coloc" check "$case" --ranks "$np" \
      --draw "$work/no/such/dir/x.svg" || fail "an unwritable picture"
    ;;
  drawplane)
    for pl in "" yz xy; do
      args=()
      [[ -n $pl ]] && args=(--plane "$pl")
      timeout 60 "$coloc" check "$case" --ranks 2 --set 'partition.dims=[1,2,1]' \
        --draw "$work/p$pl.svg" "${args[@]}" > "$work/p$pl.txt" 2>&1 ||
        { cat "$work/p$pl.txt"; fail "coloc check --draw ${args[*]}"; }
    done
    "$py" - "$work" <<'EOF2' || fail "the planes drawn"
import sys
import xml.etree.ElementTree as ET
work = sys.argv[1]
def blocks(name):
    svg = ET.parse(f"{work}/{name}.svg").getroot()
    panel = next(g for g in svg.iter("{http://www.w3.org/2000/svg}g")
                 if g.get("class") == "panel" and g.get("data-strategy") == "uniform")
    text = " ".join(t.text or "" for t in svg.iter("{http://www.w3.org/2000/svg}text"))
    return sorted((int(r.get("data-rank")), r.get("data-lo"), r.get("data-hi"))
                  for r in panel.iter("{http://www.w3.org/2000/svg}rect")
                  if r.get("class") == "block"), text
b, t = blocks("p")
print("default:", b)
assert len(b) == 1 and "The plane y = " in t, (b, t)
b, t = blocks("pyz")
print("yz:", b)
# across y (4 cells, cut at 2), up z (16 cells)
assert b == [(0, "0 0", "2 16"), (1, "2 0", "4 16")], b
assert "The plane x = " in t and "y: 0 .. 0.01 m (4 cells)" in t, t
b, t = blocks("pxy")
print("xy:", b)
# across x (4 cells, whole), up y (cut at 2)
assert b == [(0, "0 0", "4 2"), (1, "0 2", "4 4")], b
assert "The plane z = " in t, t
print("planes: default one rank, yz and xy both")
EOF2
    "$expect" "--plane" -- "$coloc" check "$case" --ranks 2 --plane yz || fail "--plane without --draw"
    "$expect" "--plane: zz not in" -- "$coloc" check "$case" --ranks 2 --draw "$work/x.svg" \
      --plane zz || fail "a bad plane"
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test"

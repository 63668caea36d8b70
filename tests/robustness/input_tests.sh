#!/usr/bin/env bash
# input_tests.sh TEST COLOC MPIEXEC PYTHON BED INFLOW WORKDIR — numbers that do not fit, memory the
# estimate must see, and what a run says of itself (issue 27: docs/robustness.md,
# docs/case-files.md). BED is cases/bed.json, INFLOW cases/inflow.json. Each run is bounded by
# `timeout`: a hang fails the test instead of stalling it.
#
#   inflow_rate       rate 1e300: refused naming particles.inflow[0].rate (check and run)
#   inflow_mass_rate  mass_rate 1e12: refused naming .mass_rate, no hang in the insertion loop
#   inflow_waiting    more due a DEM step than the patch has sites: refused (waiting list); a
#                     waiting list larger than run.memory_limit: refused by the memory estimate
#   skin              particles.skin = 1e20: refused naming the key (check and run), no hang
#   failure_wait      run.failure_wait_s = 1e10: refused; 1e6 with a failure: clean exit 3
#   ranks             coloc check --ranks 2147483647: exit 2 naming --ranks, no SIGFPE
#   rlimit_as         an address-space limit (ulimit -v): refused by the estimate (RLIMIT_AS), or,
#                     with run.memory_limit forcing the run, "out of memory" with a report
#   restart_changes   a restart with another density and source count: the notes and
#                     report.json restart.{kept_from_checkpoint,taken_from_case}
#   restart_nothing   a restart whose run.steps is at the checkpoint's step: exit 2, report failed
#   provenance        report.json's provenance: every key, each plausible (the date now, this
#                     host, cores online, the rank count, oversubscribed exactly when a node has
#                     more ranks than cores, the source tree's git commit, the version of the top
#                     CMakeLists.txt, the MPI / hypre / HDF5 versions, the command line)
#   log               OUT/log.txt holds what rank 0 prints, the progress table included (also with
#                     --quiet, which keeps the phase table off the terminal only); the phase
#                     table's rows and sums are report.json's timers and run.wall_s; the figure of
#                     merit line is report.json's figure_of_merit, throughput over the cores used;
#                     a restart continuing in its folder appends to the log, the table's header
#                     again after its note
#   progress          the progress table (run.progress_columns, every column): one header, a row
#                     every step (run.progress_interval_s = 1e-9) from step 0; the last row against
#                     report.json (particles, contacts, time, dt, cfl, p_iter, dp); the same rows
#                     on 1 and 2 ranks (coupled and particles-only: integers exact, values to
#                     the last digit printed, 1e-6 relative for 7 digits); '-' for what the mode
#                     has not; an unknown column refused (exit 2) naming run.progress_columns
#   mpi_env           report.json provenance.mpi_env against what the run had: ranks a node; the
#                     binding by the ranks' affinity masks (--bind-to none: "none", every rank on
#                     all CPUs; --bind-to core: "exclusive", CPUs of its own); yield_when_idle as
#                     OMPI_MCA_mpi_yield_when_idle says (1: true, 0: false)
#   log_header        OUT/log.txt starts with the provenance (version and commit, the command,
#                     date and host, ranks and nodes, binding and yield, MPI, build, the case),
#                     also with --quiet, which keeps the case line in the log (off the terminal);
#                     `coloc --version` names the same commit, compiler, flags and libraries
#   progress_heat     t_fluid and t_particles (bench/cases/bed-wall-heated.json, particles
#                     hotter than the water) against the fields and particles written at the last
#                     step (eps-weighted and mass-weighted means), on 1 and 2 ranks, the particles
#                     cooling and the water warming row by row; '-' without heat
#   progress_report   report.json keys as columns (a number, an integer, an array element, a
#                     bed.* diagnostic): the last row equals report.json; a key the report does
#                     not have, and one that is not a number, refused (exit 2) naming
#                     run.progress_columns, the key and the numbers there
#   pressure_max_iter fluid.pressure.max_iter = 1: a warning and fluid.unconverged_solves; with
#                     fluid.pressure.on_no_convergence = error: exit 3 naming the key
set -u
test=$1 coloc=$2 mpiexec=$3 py=$4 bed=$5 inflow=$6 work=$7
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# run NAME CMD...: time-limited; output in $log, status in $rc
run() {
  local name=$1
  shift
  log="$work/$name.log"
  timeout 60 "$@" > "$log" 2>&1
  rc=$?
  echo "== $name: exit $rc: $*"
  cat "$log"
  [[ $rc -eq 124 ]] && fail "timed out (hang): $*"
  return 0
}
expect() {  # expect CODE TEXT: the last run's status and a line of its output
  [[ $rc -eq $1 ]] || fail "exit status $rc, expected $1"
  grep -qF -- "$2" "$log" || fail "the output does not contain: $2"
}
json() {  # json FILE EXPR: a Python expression over d (the parsed file) must hold
  "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if ($2) else 1)" "$1" ||
    fail "$1: not ($2)"
}
one=("$mpiexec" -n 1 --bind-to none)
two=("$mpiexec" -n 2 --bind-to none)

case $test in
  inflow_rate)
    run check "$coloc" check "$inflow" --set particles.inflow.0.rate=1e300
    expect 2 "coloc: error: particles.inflow[0].rate:"
    run run "${two[@]}" "$coloc" run "$inflow" --out "$work/a" --quiet \
      --set particles.inflow.0.rate=1e300
    expect 2 "coloc: error: particles.inflow[0].rate:"
    # an ordinary rate still runs
    run ok "${two[@]}" "$coloc" run "$inflow" --out "$work/b" --quiet
    expect 0 "report written"
    ;;
  inflow_mass_rate)
    run check "$coloc" check "$inflow" --set particles.inflow.0.rate=0 \
      --set particles.inflow.0.mass_rate=1e12
    expect 2 "coloc: error: particles.inflow[0].mass_rate:"
    run run "${two[@]}" "$coloc" run "$inflow" --out "$work/a" --quiet \
      --set particles.inflow.0.rate=0 --set particles.inflow.0.mass_rate=1e12
    expect 2 "coloc: error: particles.inflow[0].mass_rate:"
    ;;
  inflow_waiting)
    # 1e8/s x 5e-5 s = 5000 particles a DEM step onto 81 sites
    run check "$coloc" check "$inflow" --set particles.inflow.0.rate=1e8
    expect 2 "insertion sites: the waiting list could never be drained"
    run run "${two[@]}" "$coloc" run "$inflow" --out "$work/a" --quiet \
      --set particles.inflow.0.rate=1e8
    expect 2 "coloc: error: particles.inflow[0].rate:"
    # 1e6/s (50 a step) over 100 s: 1e8 due, 1.6 GB of waiting list on every rank
    run mem "${two[@]}" "$coloc" run "$inflow" --out "$work/b" --quiet \
      --set particles.inflow.0.rate=1e6 --set run.steps=0 --set run.end_time=100 \
      --set run.memory_limit=0.5
    expect 2 "particles.inflow: the case needs about"
    grep -qF "inflow waiting lists" "$log" || fail "the estimate does not name the waiting lists"
    ;;
  skin)
    run check "$coloc" check "$bed" --set particles.skin=1e20
    expect 2 "coloc: error: particles.skin:"
    run run "${two[@]}" "$coloc" run "$bed" --out "$work/a" --quiet --set particles.skin=1e20
    expect 2 "coloc: error: particles.skin:"
    ;;
  failure_wait)
    run check "$coloc" check "$bed" --set run.failure_wait_s=1e10
    expect 2 "coloc: error: run.failure_wait_s:"
    run run "${two[@]}" "$coloc" run "$bed" --out "$work/a" --quiet --set run.failure_wait_s=1e10
    expect 2 "coloc: error: run.failure_wait_s:"
    # the largest allowed wait runs normally (its deadline is never armed)
    run ok "${two[@]}" "$coloc" run "$bed" --out "$work/b" --quiet --set run.failure_wait_s=1e6 \
      --set run.steps=2
    expect 0 "report written"
    ;;
  ranks)
    run big "$coloc" check "$bed" --ranks 2147483647
    expect 2 "coloc: error: --ranks:"
    run max "$coloc" check "$bed" --ranks 16777216
    [[ $rc -eq 0 || $rc -eq 2 ]] || fail "exit status $rc at --ranks 16777216"
    run neg "$coloc" check "$bed" --ranks 0
    expect 2 "coloc: error: --ranks:"
    ;;
  rlimit_as)
    # the rank alone under the limit (mpirun itself is not limited)
    big=(--set 'domain.cells=[160,160,160]' --set run.mode=fluid --set run.steps=2)
    run est "$mpiexec" -n 1 --bind-to none bash -c \
      "ulimit -v $((1500 * 1024)) && exec '$coloc' run '$bed' --out '$work/a' --quiet ${big[*]}"
    expect 2 "RLIMIT_AS"
    run oom "$mpiexec" -n 1 --bind-to none bash -c \
      "ulimit -v $((1500 * 1024)) && exec '$coloc' run '$bed' --out '$work/b' --quiet ${big[*]} \
       --set run.memory_limit=100"
    [[ $rc -eq 3 ]] || fail "exit status $rc, expected 3"
    grep -qF "out of memory" "$log" || fail "no out-of-memory message"
    json "$work/b/report.json" "d['status'] == 'failed' and d['out_of_memory'] and d['exit_code'] == 3"
    ;;
  restart_changes)
    run base "${two[@]}" "$coloc" run "$bed" --out "$work/a" --quiet --set run.steps=2 \
      --set output.checkpoint_interval=2
    expect 0 "report written"
    run restart "${two[@]}" "$coloc" run "$bed" --out "$work/b" --restart "$work/a/checkpoint.h5" \
      --set run.steps=3 --set particles.materials.0.density=3000 \
      --set particles.sources.0.count=300 --set fluid.nu=2e-6
    expect 0 "kept from the checkpoint"
    grep -qF "particles.materials.0.density (2500.0 -> 3000.0)" "$log" || fail "density not noted"
    grep -qF "particles.sources.0.count (400 -> 300)" "$log" || fail "source count not noted"
    grep -qF "fluid.nu (1e-06 -> 2e-06)" "$log" || fail "nu not noted"
    json "$work/b/report.json" "'particles.materials.0.density' in d['restart']['kept_from_checkpoint'] and 'particles.sources.0.count' in d['restart']['kept_from_checkpoint'] and 'fluid.nu' in d['restart']['taken_from_case'] and d['restart']['step'] == 2"
    ;;
  restart_nothing)
    run base "${two[@]}" "$coloc" run "$bed" --out "$work/a" --quiet --set run.steps=2 \
      --set output.checkpoint_interval=2
    expect 0 "report written"
    run same "${two[@]}" "$coloc" run "$bed" --out "$work/b" --quiet \
      --restart "$work/a/checkpoint.h5" --set run.steps=2
    expect 2 "coloc: error: run.steps: 2: the checkpoint"
    json "$work/b/report.json" "d['status'] == 'failed' and d['exit_code'] == 2"
    run end "${two[@]}" "$coloc" run "$bed" --out "$work/c" --quiet \
      --restart "$work/a/checkpoint.h5" --set run.steps=0 --set run.end_time=0.001
    expect 2 "coloc: error: run.end_time:"
    ;;
  pressure_max_iter)
    run warn "${two[@]}" "$coloc" run "$bed" --out "$work/a" --quiet --set run.steps=3 \
      --set fluid.pressure.max_iter=1
    expect 0 "coloc: warning: step 1: the pressure solve did not converge"
    json "$work/a/report.json" "d['status'] == 'ok' and d['fluid']['unconverged_solves'] == 3"
    run error "${two[@]}" "$coloc" run "$bed" --out "$work/b" --quiet --set run.steps=3 \
      --set fluid.pressure.max_iter=1 --set fluid.pressure.on_no_convergence=error
    expect 3 "fluid.pressure.on_no_convergence = error: the pressure solve of fluid step 1"
    json "$work/b/report.json" "d['status'] == 'failed'"
    # the default case converges: no warning, a zero count
    run ok "${two[@]}" "$coloc" run "$bed" --out "$work/c" --quiet --set run.steps=2
    expect 0 "report written"
    grep -q "warning" "$log" && fail "a warning where every solve converged"
    json "$work/c/report.json" "d['fluid']['unconverged_solves'] == 0"
    ;;
  provenance)
    src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
    cores=$(getconf _NPROCESSORS_ONLN)
    runs=(2)
    ((cores <= 4)) && runs+=($((cores + 1)))  # one more rank than cores: oversubscribed
    for np in "${runs[@]}"; do
      run "np$np" "$mpiexec" -n "$np" --bind-to none "$coloc" run "$bed" --out "$work/np$np" \
        --quiet --set run.steps=1 --set 'description=a b'
      expect 0 "report written"
      "$py" - "$work/np$np/report.json" "$np" "$cores" "$src" "$bed" <<'PYEOF' || fail "provenance ($np ranks)"
import datetime, json, re, socket, subprocess, sys
d = json.load(open(sys.argv[1]))
np, cores, src, bed = int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
p = d["provenance"]
print(json.dumps(p, indent=1))
keys = ["date", "host", "cpu_model", "cores", "ranks", "nodes", "ranks_per_node_max",
        "oversubscribed", "cores_used", "coloc_version", "git_commit", "git_dirty", "compiler",
        "compiler_flags", "build_type", "mpi_library", "hypre_version", "hdf5_version",
        "command_line", "simulated"]
missing = [k for k in keys if k not in p]
assert not missing, missing
when = datetime.datetime.strptime(p["date"], "%Y-%m-%dT%H:%M:%SZ")
age = datetime.datetime.utcnow() - when
assert datetime.timedelta(0) <= age < datetime.timedelta(minutes=10), age
assert p["host"] == socket.gethostname(), p["host"]
assert p["cpu_model"] and p["cpu_model"] != "unknown", p["cpu_model"]
assert p["cores"] == cores and p["ranks"] == np and p["nodes"] == 1, p
assert p["ranks_per_node_max"] == np, p
assert p["oversubscribed"] is (np > cores), (np, cores, p["oversubscribed"])
assert p["simulated"] is False, p["simulated"]
assert p["cores_used"] == min(np, cores), (np, cores, p["cores_used"])
version = re.search(r"project\(coloc VERSION ([0-9.]+)", open(src + "/CMakeLists.txt").read())
assert p["coloc_version"] == version.group(1) == d["coloc_version"], p["coloc_version"]
git = subprocess.run(["git", "-C", src, "rev-parse", "HEAD"], capture_output=True, text=True)
if git.returncode == 0:
    assert re.fullmatch(r"[0-9a-f]{40}", p["git_commit"]), p["git_commit"]
    assert isinstance(p["git_dirty"], bool), p["git_dirty"]
else:
    assert p["git_commit"] == "unknown", p["git_commit"]
assert re.match(r"(GNU|Clang|AppleClang|IntelLLVM|Intel) [0-9]+\.", p["compiler"]), p["compiler"]
assert isinstance(p["build_type"], str), p["build_type"]
if p["build_type"] in ("Release", "RelWithDebInfo"):
    assert "-O" in p["compiler_flags"], p["compiler_flags"]
assert p["compiler_flags"] == p["compiler_flags"].strip(), p["compiler_flags"]
assert re.search(r"(Open MPI|MPICH|Intel\(R\) MPI|MVAPICH)", p["mpi_library"]), p["mpi_library"]
assert "\n" not in p["mpi_library"], p["mpi_library"]
assert re.fullmatch(r"[0-9]+\.[0-9]+\.[0-9]+.*", p["hypre_version"]), p["hypre_version"]
assert re.fullmatch(r"[0-9]+\.[0-9]+\.[0-9]+", p["hdf5_version"]), p["hdf5_version"]
cl = p["command_line"]
assert " run " in cl and bed in cl and "run.steps=1" in cl and "'description=a b'" in cl, cl
PYEOF
    done
    ;;
  log)
    run loud "${two[@]}" "$coloc" run "$bed" --out "$work/a" --set run.steps=4 \
      --set run.progress_interval_s=1e-9 --set output.checkpoint_interval=2
    expect 0 "report written"
    [[ -f $work/a/log.txt ]] || fail "no log.txt"
    # the default columns: a header, then a row for step 0 and for each of the 4 steps
    header="^ \+step \+time \+dt \+ke \+cfl \+p_iter \+steps_per_s \+left$"
    n=$(grep -c "$header" "$log")
    [[ $n -eq 1 ]] || fail "$n progress headers on the terminal, expected 1"
    n=$(grep -c "^ \+[0-4] " "$log")
    [[ $n -eq 5 ]] || fail "$n progress rows on the terminal, expected 5 (steps 0-4)"
    while IFS= read -r line; do
      grep -qxF -- "$line" "$work/a/log.txt" || fail "not in log.txt: $line"
    done < "$log"
    check_table() {  # check_table LOG REPORT: the table and the figure of merit against the report
      "$py" - "$1" "$2" <<'PYEOF' || fail "the phase table or the figure of merit of $1"
import json, re, sys
text, d = open(sys.argv[1]).read(), json.load(open(sys.argv[2]))
lines = text.splitlines()
start = next(i for i, l in enumerate(lines) if l.startswith("coloc:   phase (over ranks)"))
rows, sums = {}, {}
for l in lines[start + 1:]:
    m = re.match(r"coloc:   (\S+)\s+([-0-9.e+]+)\s+([-0-9.e+]+)\s+([-0-9.e+]+)\s+([-0-9.]+)$", l)
    if m:
        rows[m.group(1)] = [float(m.group(i)) for i in range(2, 6)]
        continue
    m = re.match(r"coloc:   (phases \(sum\)|other \(in no phase\)|loop \(run.wall_s\))\s+([-0-9.e+]+)\s+([-0-9.]+)$", l)
    if m:
        sums[m.group(1).split()[0]] = (float(m.group(2)), float(m.group(3)))
        continue
    if l.startswith("coloc:   setup"):
        continue
    break
close = lambda a, b: abs(a - b) <= 1e-5 * max(abs(a), abs(b)) + 1e-12
timers = {k: v for k, v in d["timers"].items() if k != "setup"}
wall = d["run"]["wall_s"]
assert set(rows) == set(timers), (sorted(rows), sorted(timers))
for k, (mn, avg, mx, pct) in rows.items():
    t = timers[k]
    assert close(mn, t["min"]) and close(avg, t["avg"]) and close(mx, t["max"]), (k, rows[k], t)
    assert abs(pct - 100 * t["avg"] / wall) < 0.006, (k, pct)
total = sum(t["avg"] for t in timers.values())
assert close(sums["phases"][0], total), (sums["phases"], total)
assert close(sums["loop"][0], wall) and close(sums["other"][0], wall - total), sums
assert abs(sums["phases"][1] + sums["other"][1] - 100) < 0.02, sums
f, p = d["figure_of_merit"], d["provenance"]
assert f["cores"] == p["cores_used"] > 0, (f, p["cores_used"])
assert close(f["particle_steps_per_s_per_core"], d["throughput"]["particle_steps_per_s"] / f["cores"])
assert close(f["cell_steps_per_s_per_core"], d["throughput"]["cell_steps_per_s"] / f["cores"])
assert f["inter_physics_share"] == d["fractions"]["inter_physics"]
m = re.search(r"^coloc: figure of merit: ([0-9.e+]+) particle-steps/s/core, ([0-9.e+]+) cell-steps/s/core, inter-physics ([0-9.e+-]+)% of the step \((\d+) cores?\)$", text, re.M)
assert m, "no figure-of-merit line"
assert abs(float(m.group(1)) / f["particle_steps_per_s_per_core"] - 1) < 1e-3, m.group(1)
assert abs(float(m.group(2)) / f["cell_steps_per_s_per_core"] - 1) < 1e-3, m.group(2)
assert int(m.group(4)) == f["cores"]
print("table:", len(rows), "phases, sum", total, "of", wall, "s; figure of merit", f)
PYEOF
    }
    check_table "$work/a/log.txt" "$work/a/report.json"
    # --quiet: the table in the log only
    run quiet "${two[@]}" "$coloc" run "$bed" --out "$work/q" --quiet --set run.steps=2
    expect 0 "figure of merit"
    grep -q "phase (over ranks)" "$log" && fail "--quiet printed the phase table"
    check_table "$work/q/log.txt" "$work/q/report.json"
    # a restart continuing in its folder: the log goes on
    run more "${two[@]}" "$coloc" run "$bed" --out "$work/a" --set run.steps=6 \
      --set run.progress_interval_s=1e-9 --restart "$work/a/checkpoint.h5"
    expect 0 "report written"
    grep -q "^ \+2 " "$work/a/log.txt" || fail "the restart dropped the earlier log"
    grep -q "^coloc: ---- the run continues (--restart) ----" "$work/a/log.txt" || fail "no mark"
    # after the mark and the restart's note: the header again, rows from step 4 (the checkpoint's)
    sed -n '/^coloc: ---- the run continues/,$p' "$work/a/log.txt" > "$work/more.txt"
    [[ $(grep -c "$header" "$work/more.txt") -eq 1 ]] || fail "no header after the restart"
    note=$(grep -n "^coloc: restarted from" "$work/more.txt" | cut -d: -f1)
    at=$(grep -n "$header" "$work/more.txt" | cut -d: -f1)
    [[ -n $note && $at -gt $note ]] || fail "the header does not follow the restart's note"
    [[ $(grep -c "^ \+[4-6] " "$work/more.txt") -eq 3 ]] ||
      fail "the restart's rows are not steps 4, 5, 6"
    ;;
  progress)
    cols=step,time,dt,particles,ke,contacts,cfl,p_iter,p_iter_avg,dp,wall_per_step,steps_per_s,left
    for np in 1 2; do
      run "np$np" "$mpiexec" -n $np --bind-to none "$coloc" run "$bed" --out "$work/np$np" \
        --set run.steps=5 --set run.progress_interval_s=1e-9 --set "run.progress_columns=$cols"
      expect 0 "report written"
    done
    # particles only, and fluid only: what the mode has not is '-'
    for np in 1 2; do
      run "dem$np" "$mpiexec" -n $np --bind-to none "$coloc" run "$bed" --out "$work/dem$np" \
        --set run.mode=particles --set run.steps=5 --set run.progress_interval_s=1e-9 \
        --set "run.progress_columns=step particles ke contacts cfl p_iter dp"
      expect 0 "report written"
    done
    run fluid "${two[@]}" "$coloc" run "$bed" --out "$work/fluid" --set run.mode=fluid \
      --set run.steps=3 --set run.progress_interval_s=1e-9 \
      --set 'run.progress_columns=["step","particles","ke","contacts","cfl","p_iter","dp"]'
    expect 0 "report written"
    "$py" - "$work" "$cols" <<'PYEOF' || fail "the progress tables"
import json, sys
work, cols = sys.argv[1], sys.argv[2].split(",")
def table(folder, names):
    lines = open(f"{work}/{folder}/log.txt").read().splitlines()
    heads = [i for i, l in enumerate(lines) if l.split() == names]
    assert len(heads) == 1, (folder, "headers", heads)
    rows = []
    for l in lines[heads[0] + 1:]:
        f = l.split()
        if len(f) != len(names) or not f[0].isdigit() or not l.startswith(" "):
            continue
        rows.append(dict(zip(names, f)))
    assert [int(r["step"]) for r in rows] == list(range(len(rows))), (folder, rows)
    return rows, json.load(open(f"{work}/{folder}/report.json"))
def close(a, b, rel=1e-6, abs_=0.0):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_
every = {}
for np in (1, 2):
    rows, d = table(f"np{np}", cols)
    assert len(rows) == 6, (np, len(rows))
    first, last = rows[0], rows[-1]
    for c in ("dt", "cfl", "p_iter", "p_iter_avg", "wall_per_step", "steps_per_s", "left"):
        assert first[c] == "-", (np, c, first)
    assert all(v != "-" for r in rows[1:] for v in r.values()), (np, rows)
    assert float(last["left"]) == 0, last
    assert int(last["step"]) == d["run"]["steps"] == 5
    assert int(last["particles"]) == d["particles"]["count"] == 400, (last, d["particles"]["count"])
    assert close(float(last["contacts"]), d["particles"]["contacts_per_particle"], 1e-4), last
    assert close(float(last["time"]), d["run"]["sim_time"]), last
    assert close(float(last["dt"]), d["fluid"]["dt_last"], 1e-3), last
    assert close(float(last["cfl"]), d["fluid"]["cfl_last"], 1e-3), last
    assert int(last["p_iter"]) == d["pressure"]["iterations_last"], last
    assert close(float(last["p_iter_avg"]), d["pressure"]["iterations_avg"], 1e-3), last
    assert close(float(last["dp"]), d["bed"]["dp_box_pa"], 1e-6, 1e-9), (last, d["bed"])
    assert float(rows[0]["ke"]) == 0 and all(float(r["ke"]) > 0 for r in rows[1:]), rows
    every[np] = rows
    print(f"np{np}: 6 rows; last", " ".join(last[c] for c in cols))
# to the last digit printed: 7 significant digits, 4 for dt, cfl, p_iter_avg, 5 for contacts
digits = {"dt": 4, "cfl": 4, "p_iter_avg": 4, "contacts": 5}
def same(a, b, names, ints):
    assert len(a) == len(b), (len(a), len(b))
    for ra, rb in zip(a, b):
        for c in names:
            if c in ints:
                assert ra[c] == rb[c], (c, ra, rb)
            elif ra[c] == "-" or rb[c] == "-":
                assert ra[c] == rb[c], (c, ra, rb)
            else:
                rel = 10.0 ** (1 - digits.get(c, 7))
                assert close(float(ra[c]), float(rb[c]), rel, 1e-300), (c, ra, rb)
same(every[1], every[2], cols[:10], {"step", "particles", "p_iter"})
dem = "step particles ke contacts cfl p_iter dp".split()
d1, _ = table("dem1", dem)
d2, _ = table("dem2", dem)
same(d1, d2, dem, {"step", "particles"})
assert all(r[c] == "-" for r in d1 for c in ("cfl", "p_iter", "dp")), d1
assert all(r["particles"] == "400" for r in d1), d1
fl, _ = table("fluid", dem)
assert len(fl) == 4, fl
assert all(r[c] == "-" for r in fl for c in ("particles", "ke", "contacts")), fl
assert all(r[c] != "-" for r in fl[1:] for c in ("cfl", "p_iter", "dp")), fl
print("1 and 2 ranks agree; particles-only and fluid-only rows as expected")
PYEOF
    # an unknown column: refused before the run, naming the key, the name and the valid ones
    run bad "${two[@]}" "$coloc" run "$bed" --out "$work/bad" --set run.progress_columns=step,kinetic
    expect 2 "run.progress_columns: unknown name 'kinetic', expected some of: step, time, dt,"
    [[ -e $work/bad ]] && fail "the refused run made its folder"
    run keys "$coloc" keys run
    expect 0 "run.progress_columns  (a list of names, default [\"step\",\"time\",\"dt\",\"ke\""
    ;;
  mpi_env)
    cores=$(getconf _NPROCESSORS_ONLN)
    run none "${two[@]}" "$coloc" run "$bed" --out "$work/none" --quiet --set run.steps=1
    expect 0 "report written"
    allowed=$("$py" -c "import os; print(len(os.sched_getaffinity(0)))")
    json "$work/none/report.json" "d['provenance']['mpi_env'] == dict(d['provenance']['mpi_env'], ranks_per_node_min=2, ranks_per_node_max=2, binding='none', cpus_per_rank_min=$allowed, cpus_per_rank_max=$allowed, yield_when_idle=True)"
    if ((cores >= 2 && allowed >= 2)); then
      OMPI_MCA_mpi_yield_when_idle=0 run core "$mpiexec" -n 2 --bind-to core "$coloc" run "$bed" \
        --out "$work/core" --quiet --set run.steps=1
      expect 0 "report written"
      json "$work/core/report.json" "d['provenance']['mpi_env']['binding'] == 'exclusive' and d['provenance']['mpi_env']['yield_when_idle'] is False and 1 <= d['provenance']['mpi_env']['cpus_per_rank_max'] < $allowed"
    fi
    "$py" -c "import json,sys; print(json.dumps(json.load(open(sys.argv[1]))['provenance']['mpi_env']))" "$work/none/report.json"
    ;;
  log_header)
    run quiet "${two[@]}" "$coloc" run "$bed" --out "$work/q" --quiet --set run.steps=2
    expect 0 "report written"
    grep -q "^coloc: case 'ck-bed'" "$log" && fail "--quiet printed the case line"
    run version "$coloc" --version
    expect 0 "coloc "
    "$py" - "$work/q/log.txt" "$work/q/report.json" "$log" "$bed" <<'PYEOF' || fail "the log header"
import json, re, sys
lines = open(sys.argv[1]).read().splitlines()
d = json.load(open(sys.argv[2]))
version = open(sys.argv[3]).read()
bed = sys.argv[4]
p, e = d["provenance"], d["provenance"]["mpi_env"]
print("\n".join(lines[:8]))
assert lines[0].startswith(f"coloc: coloc {p['coloc_version']}, git {p['git_commit']}"), lines[0]
assert lines[1] == f"coloc: command: {p['command_line']}", lines[1]
assert lines[2].startswith(f"coloc: {p['date']} on {p['host']} ({p['cpu_model']}, {p['cores']} cores"), lines[2]
assert lines[3].startswith(f"coloc: 2 rank(s) on 1 node(s), 2-2 a node"), lines[3]
assert f"binding {e['binding']} (rank 0 on CPUs {e['cpus_rank0']})" in lines[3], lines[3]
assert lines[3].endswith(f"yield when idle {json.dumps(e['yield_when_idle'])}"), lines[3]
assert lines[4] == f"coloc: MPI: {p['mpi_library']}", lines[4]
assert lines[5].startswith(f"coloc: build: {p['compiler']} {p['build_type']}, flags {p['compiler_flags']}; hypre {p['hypre_version']}, HDF5 {p['hdf5_version']}"), lines[5]
assert lines[6] == f"coloc: case file {bed}, output folder " + sys.argv[1][:-len("/log.txt")], lines[6]
assert any(l.startswith("coloc: case 'ck-bed', mode coupled, 2 rank(s)") for l in lines), "no case line"
# coloc --version: the same build
print(version)
v = dict(re.findall(r"^  ([\w ]+?):\s+(.*)$", version, re.M))
assert version.startswith(f"coloc {p['coloc_version']}\n"), version
assert v["git commit"].split()[0] == p["git_commit"], v
assert v["compiler"] == f"{p['compiler']}, {p['build_type']}", v
assert v["flags"] == p["compiler_flags"], v
assert v["MPI"] == p["mpi_library"], v
assert v["hypre"] == p["hypre_version"] and v["HDF5"].split()[0] == p["hdf5_version"], v
assert re.match(r"[0-9]+\.[0-9]+\.[0-9]+$", v["SLEEF"]), v
assert re.match(r"Eigen [0-9.]+, \{fmt\} [0-9.]+, nlohmann_json [0-9.]+, CLI11 [0-9.]+$", v["headers"]), v
print("log header and --version agree with the report's provenance")
PYEOF
    ;;
  progress_heat)
    src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
    heated=$src/bench/cases/bed-wall-heated.json
    cols=step,t_fluid,t_particles
    for np in 1 2; do
      run "np$np" "$mpiexec" -n $np --bind-to none "$coloc" run "$heated" --out "$work/np$np" \
        --set run.steps=4 --set run.progress_interval_s=1e-9 --set "run.progress_columns=$cols" \
        --set particles.sources.0.temperature=350 --set output.interval_steps=4 \
        --set output.snapshot=false
      expect 0 "report written"
    done
    run cold "${two[@]}" "$coloc" run "$bed" --out "$work/cold" --set run.steps=1 \
      --set run.progress_interval_s=1e-9 --set "run.progress_columns=$cols"
    expect 0 "report written"
    "$py" - "$work" <<'PYEOF' || fail "the temperature columns"
import json, sys
import h5py
import numpy as np
work = sys.argv[1]
def rows(folder):
    lines = open(f"{work}/{folder}/log.txt").read().splitlines()
    h = [i for i, l in enumerate(lines) if l.split() == ["step", "t_fluid", "t_particles"]]
    assert len(h) == 1, h
    return [l.split() for l in lines[h[0] + 1:] if l.startswith(" ") and l.split()[0].isdigit()]
for np_ in (1, 2):
    r = rows(f"np{np_}")
    assert [int(x[0]) for x in r] == list(range(5)), r
    tf = [float(x[1]) for x in r]
    tp = [float(x[2]) for x in r]
    print(np_, "ranks:", tf, tp)
    assert tf[0] == 300 and tp[0] == 350, (tf[0], tp[0])
    assert all(b > a for a, b in zip(tf, tf[1:])), ("the water does not warm", tf)
    assert all(b < a for a, b in zip(tp, tp[1:])), ("the particles do not cool", tp)
    with h5py.File(f"{work}/np{np_}/fields_000004.h5") as f:
        eps, T = f["eps"][...], f["T"][...]
    with h5py.File(f"{work}/np{np_}/particles_000004.h5") as f:
        w, Tp = f["radius"][...] ** 3, f["temperature"][...]   # one material: mass ~ r^3
    want_f = float((eps * T).sum() / eps.sum())
    want_p = float((w * Tp).sum() / w.sum())
    assert abs(tf[-1] - want_f) <= 1e-6 * want_f, (tf[-1], want_f)
    assert abs(tp[-1] - want_p) <= 1e-6 * want_p, (tp[-1], want_p)
assert rows("np1") == rows("np2") or all(
    abs(float(a[i]) - float(b[i])) <= 1e-6 * float(a[i]) for a, b in zip(rows("np1"), rows("np2"))
    for i in (1, 2))
c = rows("cold")
assert all(x[1] == "-" and x[2] == "-" for x in c), c
print("t_fluid and t_particles are the fields' and particles' means; '-' without heat")
PYEOF
    ;;
  progress_report)
    cols="step,fluid.cfl_last,particles.count,fluid.drag_force.2,timers.dem_force.calls,bed.bed_height_m,checks.momentum_balance"
    run rep "${two[@]}" "$coloc" run "$bed" --out "$work/rep" --set run.steps=3 \
      --set run.progress_interval_s=1e-9 --set "run.progress_columns=$cols"
    expect 0 "report written"
    "$py" - "$work/rep" "$cols" <<'PYEOF' || fail "report columns"
import json, sys
folder, cols = sys.argv[1], sys.argv[2].split(",")
lines = open(f"{folder}/log.txt").read().splitlines()
h = [i for i, l in enumerate(lines) if l.split() == cols]
assert len(h) == 1, ("one header", h)
rows = [dict(zip(cols, l.split())) for l in lines[h[0] + 1:]
        if l.startswith(" ") and l.split()[0].isdigit() and len(l.split()) == len(cols)]
assert [int(r["step"]) for r in rows] == [0, 1, 2, 3], rows
d = json.load(open(f"{folder}/report.json"))
last = rows[-1]
def val(key):
    v = d
    for k in key.split("."):
        v = v[int(k)] if isinstance(v, list) else v[k]
    return v
for c in cols[1:]:
    want = val(c)
    if isinstance(want, int):
        assert int(last[c]) == want, (c, last[c], want)
    else:
        assert abs(float(last[c]) - want) <= 1e-6 * abs(want) + 1e-300, (c, last[c], want)
print("last row = report.json:", last)
PYEOF
    run nokey "${two[@]}" "$coloc" run "$bed" --out "$work/nokey" --set run.steps=1 \
      --set run.progress_columns=step,fluid.cfl_lats
    expect 2 "run.progress_columns: 'fluid.cfl_lats' is no key of this run's report; numbers under 'fluid': fluid.steps,"
    run notnum "${two[@]}" "$coloc" run "$bed" --out "$work/notnum" --set run.steps=1 \
      --set run.progress_columns=step,fluid.drag_force
    expect 2 "run.progress_columns: 'fluid.drag_force' is not a number of this run's report; numbers under 'fluid.drag_force': fluid.drag_force.0, fluid.drag_force.1, fluid.drag_force.2"
    run dots "${two[@]}" "$coloc" run "$bed" --out "$work/dots" --set run.steps=1 \
      --set run.progress_columns=step,fluid..x
    expect 2 "run.progress_columns: 'fluid..x' is not a key path of report.json"
    ;;
  *) fail "unknown test $test" ;;
esac
echo "PASS: $test"

#!/usr/bin/env python3
"""Validate the performance model (bench/scripts/model.py) at 1 and 2 ranks on this machine.

For each case (default case2-small and case3-small) it runs, --repeats times each:
  np1        mpirun -n 1 coloc run CASE                      (the calibration)
  np1corun   the same beside one `bench_stream --co-run`      (memory-bound shares)
  np2        mpirun -n 2 coloc run CASE                      (the point to predict)
and once: bench_stream on every core (memory contention), bench_pingpong (the network, --repeats
times, median; --no-pingpong: --pingpong's file), bench_fv BM_PressureSolve/{32,64}/0 and
BM_PressureSolveBox on the small cases' grids on 1 and 2 ranks (hypre's per-level overhead and
the solve's contention, fitted together from the two cubes), `coloc plan CASE --ranks 1,2`; and
before each repeat's runs bench_noise (the cores' uneven speed on the same work: a pair loop and
a triad at the stream working set; --no-noise: neither measured nor modelled). It takes the
median of each set (--pick median, the default: one calibration from each 1-rank run and its
co-run, every input the median over the repeats, bench_stream run --repeats times and
bench_fv's repetitions by their median too; --pick min: the fastest run of each), calibrates from
the 1-rank runs ONLY (the 2-rank runs are never fitted), predicts 1 and 2 ranks (--ranks: more) with the
measured ping-pong and stream profile and prints, per point, the model and measured step time
and shares (fluid, DEM, coupling, inter-physics, wait) with their errors, PASS/FAIL against
15 % (a share: 15 % of the measured share, or 1.5 points where that is larger). `uptime` is
recorded before and after. The runs set run.timer_sync (--no-timer-sync: not): a timed barrier
before the fluid's halo after the predictor and before the DEM's rebuild vote books a rank's
wait for the slowest one to `sync`, as the model books imbalance to `wait`, instead of to the
halo or the pressure solve that follows.
Writes OUT/validate-CASE.{csv,txt} and OUT/validate-costs-CASE.json.

  bench/scripts/validate_model.py                      # runs everything (a few minutes, quiet)
  bench/scripts/validate_model.py --reports DIR        # takes DIR's reports, runs nothing
  validate_model.py --cases bench/cases/case3-small.json --restart SETTLED.h5
      --settled-steps 200 --steps 10     # a bed in contact (contact_bench.py --settle-only)
  --timer busy|wall   busy (thread-CPU; default, for a loaded machine) or wall (a quiet one)

DIR layout (what a run leaves under --runs): stream-I.json (or stream.json), pingpong-I.json
(optional), pfmg-np1.json, pfmg-np2.json, CASE/plan/plan.json, CASE/noise-{pairs,triad}-I.json
(optional), CASE/{np1,np1corun,np2}-I/report.json.
"""
import argparse
import glob
import json
import os
import shlex
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dense_bed  # noqa: E402
import model  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOL = 0.15
SHARE_FLOOR = 0.015
SHARES = ["fluid", "dem", "coupling", "inter_physics", "wait"]
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_mpi_yield_when_idle": "1",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none"}


def uptime():
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        with open("/proc/loadavg") as f:
            return "loadavg " + f.read().strip()


def sh(cmd, log):
    with open(log, "w") as f:
        subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, check=True, cwd=ROOT)


def mpirun(n):
    return ["mpirun", "-n", str(n), "--bind-to", "none"]


def run_all(a, runs):
    os.environ.update({k: v for k, v in MPI_ENV.items() if k not in os.environ})
    os.makedirs(runs, exist_ok=True)
    bench = a.bench
    ncores = a.stream_ranks or os.cpu_count() or 2
    for i in range(a.repeats):
        print("measuring the memory contention (bench_stream on %d ranks) %d/%d ..."
              % (ncores, i + 1, a.repeats), flush=True)
        sh(mpirun(ncores) + [os.path.join(bench, "bench_stream"), "--json",
                             os.path.join(runs, "stream-%d.json" % i)],
           os.path.join(runs, "stream-%d.log" % i))
    stream = stream_of(runs)
    with open(os.path.join(runs, "stream.json"), "w") as f:
        json.dump(stream, f, indent=1)
    mib = model.stream_memory(stream)["size_mib"]
    if a.measure_pingpong:
        for i in range(a.repeats):
            print("measuring the ping-pong %d/%d ..." % (i + 1, a.repeats), flush=True)
            sh(mpirun(2) + [os.path.join(bench, "bench_pingpong"), "--json",
                            os.path.join(runs, "pingpong-%d.json" % i)],
               os.path.join(runs, "pingpong-%d.log" % i))
        with open(os.path.join(runs, "pingpong-median.json"), "w") as f:
            json.dump(pingpong_of(runs, a.pingpong)[0], f, indent=1)
    fv = os.path.join(bench, "bench_fv")
    if os.path.exists(fv):
        for n in (1, 2):
            print("measuring the pressure solve on %d rank(s) (bench_fv) ..." % n, flush=True)
            sh(mpirun(n) + [fv, "--benchmark_filter=BM_PressureSolve(/(32|64)/0/|Box/(72/6/72|110/22/22)/0/)",
                            "--benchmark_format=json", "--benchmark_repetitions=%d" % a.repeats,
                            "--benchmark_out=" + os.path.join(runs, "pfmg-np%d.json" % n)],
               os.path.join(runs, "pfmg-np%d.log" % n))
    base_sets = [x for kv in a.set for x in ("--set", kv)]
    for case in a.cases:
        name = os.path.splitext(os.path.basename(case))[0]
        d = os.path.join(runs, name)
        os.makedirs(d, exist_ok=True)
        sets = base_sets
        if a.dense_bed:  # the bed starts in contact (bench/scripts/dense_bed.py)
            sets = sets + ["--set", dense_bed.set_argument(case, a.dense_bed)]
        sh([a.coloc, "plan", case, "--ranks", ",".join(str(P) for P in [1] + a.ranks),
            "--strategy", "uniform", "--out",
            os.path.join(d, "plan")] + sets, os.path.join(d, "plan.log"))
        extra = ["--set", "run.steps=%d" % (a.settled_steps + a.steps)] if a.steps else []
        extra += sets
        if a.restart:  # every run continues from the same checkpoint (e.g. a settled bed)
            extra = ["--restart", os.path.abspath(a.restart)] + extra
        if a.timer_sync:  # the wait for the slowest rank booked to `sync` (fractions.wait)
            extra += ["--set", "run.timer_sync=true"]
        for i in range(a.repeats):
            if a.noise:  # the machine's noise just before the runs of this repeat
                for kern in ("pairs", "triad"):
                    sh(mpirun(max(a.ranks)) + [os.path.join(bench, "bench_noise"), "--kernel",
                                               kern, "--mib", str(mib), "--json",
                                               os.path.join(d, "noise-%s-%d.json" % (kern, i))],
                       os.path.join(d, "noise-%s-%d.log" % (kern, i)))
            for kind in ["np1", "np1corun"] + ["np%d" % P for P in a.ranks]:
                out = os.path.join(d, "%s-%d" % (kind, i))
                print("%s %s %d/%d  (%s)" % (name, kind, i + 1, a.repeats, uptime()), flush=True)
                nr = 1 if kind in ("np1", "np1corun") else int(kind[2:])
                cmd = mpirun(nr) + [a.coloc, "run", case, "--overwrite", "--out", out] + extra
                co = None
                if kind == "np1corun" and a.corunner == "self":
                    # the same 1-rank run on the other core, over and over until this one ends;
                    # then the loop stops after its current run (killing mpirun would orphan
                    # the coloc it started, which would run on beside the next runs)
                    partner = " ".join(shlex.quote(x) for x in mpirun(1) + [
                        a.coloc, "run", case, "--overwrite", "--out", out + "-partner"] + extra)
                    stop = shlex.quote(out + "-partner.stop")
                    co = subprocess.Popen(["bash", "-c", "rm -f %s; while [ ! -e %s ]; do %s; "
                                           "done" % (stop, stop, partner)],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                          start_new_session=True, cwd=ROOT)
                    time.sleep(0.5)  # past its set-up
                elif kind == "np1corun":
                    co = subprocess.Popen(mpirun(1) + [os.path.join(bench, "bench_stream"),
                                                       "--co-run", "3600", "--mib", str(mib)],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                          start_new_session=True, cwd=ROOT)
                    time.sleep(1.0)  # its arrays are allocated and streaming
                try:
                    sh(cmd, out + ".log")
                finally:
                    if co is not None and kind == "np1corun" and a.corunner == "self":
                        open(out + "-partner.stop", "w").close()
                        co.wait()
                    elif co is not None:
                        os.killpg(co.pid, signal.SIGTERM)
                        co.wait()


def load(path):
    with open(path) as f:
        return json.load(f)


def stream_of(runs):
    """bench_stream of the runs: the element-wise median of stream-I.json (one a repeat), or
    stream.json alone (folders written before the repeats)."""
    reps = sorted(glob.glob(os.path.join(runs, "stream-*.json")))
    if not reps:
        return load(os.path.join(runs, "stream.json"))
    return model.median_stream([load(p) for p in reps])


def pingpong_of(runs, fallback):
    """The network of the runs: the median of pingpong-I.json (one a repeat), or the file
    --pingpong names where the runs measured none; and where it came from."""
    reps = sorted(glob.glob(os.path.join(runs, "pingpong-[0-9]*.json")))
    if not reps:
        return load(fallback), fallback
    return model.median_of([load(p) for p in reps]), "median of %d during the runs" % len(reps)


def steps_of(r):
    return r["run"]["steps"] - r["run"].get("first_step", 0)


def busy_step(r):
    """The slowest rank's thread-CPU time of a step: its compute phases plus the mean of the
    exchange phases (they are not in load.busy_s_max)."""
    tm = r["timers"]
    ex = sum(tm.get(k, {}).get("busy_avg", 0.0) for k in
             ("fluid_halo", "dem_ghost", "dem_migrate", "exchange_local", "exchange_remote"))
    return (r["load"]["busy_s_max"] + ex) / steps_of(r)


def step_time(r, timer):
    return busy_step(r) if timer == "busy" else r["run"]["wall_s"] / steps_of(r)


def pick(reports, timer, how):
    rs = sorted(reports, key=lambda r: step_time(r, timer))
    return rs[0] if how == "min" else rs[(len(rs) - 1) // 2]


def measured_shares(r, timer):
    if timer == "wall":
        f = r["fractions"]
        return {"fluid": f["fv"], "dem": f["dem"], "coupling": f["coupling"],
                "inter_physics": f["inter_physics"], "wait": f["wait"]}
    tm = r["timers"]

    def b(names):
        return sum(tm.get(k, {}).get("busy_avg", 0.0) for k in names) / steps_of(r)

    st = busy_step(r)
    out = {"fluid": b(sum([model.GROUPS[g] for g in ("fluid", "pressure_setup", "pressure_solve")],
                          []) + ["fluid_halo"]),
           "dem": b(model.GROUPS["dem"] + ["dem_ghost"]),
           "coupling": b(model.GROUPS["coupling"]),
           "inter_physics": b(["exchange_local", "exchange_remote"])}
    out = {k: v / st for k, v in out.items()}
    out["wait"] = max(0.0, 1.0 - sum(out.values()))
    return out


def verdict(q, model_v, meas):
    if q == "step_s":
        err = (model_v - meas) / meas if meas > 0 else float("inf")
        return err, abs(err) <= TOL
    err = model_v - meas  # points
    return err, abs(err) <= max(TOL * meas, SHARE_FLOOR)


def validate_case(a, runs, case, out_dir):
    name = os.path.splitext(os.path.basename(case))[0]
    d = os.path.join(runs, name)
    rep = {k: [load(p) for p in sorted(glob.glob(os.path.join(d, k + "-*", "report.json")))]
           for k in ["np1", "np1corun"] + ["np%d" % P for P in a.ranks]}
    if not all(rep["np%d" % P] for P in [1] + a.ranks):
        raise SystemExit("validate_model: missing np1 or np%s reports under %s" %
                         ("/np".join(str(P) for P in a.ranks), d))
    key = "busy_avg" if a.timer == "busy" else "avg"
    stream = stream_of(runs)
    pp, pp_from = pingpong_of(runs, a.pingpong)
    p1 = os.path.join(runs, "pfmg-np1.json")
    p2 = os.path.join(runs, "pfmg-np2.json")
    have_fv = os.path.exists(p1) and os.path.exists(p2)
    pf1, pf2 = (load(p1), load(p2)) if have_fv else (None, None)
    if a.pick == "median":  # one calibration a repeat, each input their median
        costs = model.calibrate_median(rep["np1"], key, rep["np1corun"], stream, pf1, pf2,
                                       pp["latency_s"], a.overhead_grid)
    else:
        np1 = pick(rep["np1"], a.timer, a.pick)
        corun = pick(rep["np1corun"], a.timer, a.pick) if rep["np1corun"] else None
        costs = model.calibrate(np1, key, corun, stream, pf1, pf2, pp["latency_s"],
                                a.overhead_grid)
    src = costs["source"]
    if os.path.isabs(src) and "/bench/cases/" in src:  # reports of runs made from a checkout
        costs["source"] = "bench/cases/" + src.split("/bench/cases/")[-1]
    prof = model.profile(pp, stream)
    noises = sorted(glob.glob(os.path.join(d, "noise-*-*.json")))
    if noises and a.noise:
        prof["noise"] = model.noise_of([load(p) for p in noises])
    plan = load(os.path.join(d, "plan", "plan.json"))
    rows, lines = [], []
    lines.append("MODEL VALIDATION %s, timer %s, %d repeat(s), %s of each, calibrated on 1 rank%s"
                 % (name, a.timer, len(rep["np1"]), a.pick,
                    "; run.timer_sync" if a.timer_sync else ""))
    lines.append("load during the runs: %s" % a.load_note)
    lines.append("memory: contention c(2) = %.3f (bench_stream, %.0f MiB a rank), memory-bound "
                 "shares %s" % (model.contention(prof["memory"], 2), prof["memory"]["size_mib"],
                                ", ".join("%s %.2f" % kv for kv in costs["memory_share"].items())))
    ov = costs["pressure_overhead"]
    lines.append("pressure: %.2f PCG iterations a step (1 rank), %.2f set-ups a step; hypre "
                 "overhead per level and neighbour %.3g s an iteration, %.3g s a set-up (from %s)"
                 % (costs["pressure_iterations_per_step"], costs["pressure_setups_per_step"],
                    ov["per_level_neighbour_iteration_s"], ov["per_level_neighbour_setup_s"],
                    ov.get("from", "none")))
    lines.append("network: latency %.3g s, bandwidth %.3g B/s (ping-pong, %s)"
                 % (pp["latency_s"], pp["bandwidth_Bps"], pp_from))
    nz = prof.get("noise")
    lines.append("noise: %s" % ("none (not measured: --no-noise)" if not nz else ", ".join(
        "%s eta(%s) = %.4f (bench_noise %s, median of %d)" % (
            k, kk, v, "pair loop" if k == "compute" else "triad %.0f MiB" % nz[k]["mib"],
            nz[k]["repeats"]) for k in ("compute", "memory") if k in nz
        for kk, v in sorted(nz[k]["by_ranks"].items()))))
    lines.append("%-6s %-14s %11s %11s %9s  %s" % ("ranks", "quantity", "model", "measured",
                                                  "error", "verdict"))
    ok_all = True
    for P in [1] + a.ranks:
        reports = rep["np%d" % P]
        meas = pick(reports, a.timer, a.pick)
        lay = [L for L in plan["layouts"] if L["ranks"] == P and L["strategy"] == "uniform"][0]
        m = model.predict_layout(costs, lay, prof)
        ms = measured_shares(meas, a.timer)
        mm = {k: m[k] for k in SHARES}  # both: fractions of the slowest rank's step
        its = meas.get("pressure", {}).get("iterations_avg", 0.0)
        quantities = [("step_s", m["step_s"], step_time(meas, a.timer))]
        quantities += [(k, mm[k], ms[k]) for k in SHARES]
        for q, mv, xv in quantities:
            err, ok = verdict(q, mv, xv)
            fitted = P == 1
            tag = "(fitted)" if fitted else ("PASS" if ok else "FAIL")
            if not fitted:
                ok_all = ok_all and ok
            rows.append([name, P, a.timer, q, mv, xv, err, tag])
            if q == "step_s":
                lines.append("%-6d %-14s %11.5f %11.5f %+8.1f%%  %s" %
                             (P, q, mv, xv, 100 * err, tag))
            else:
                lines.append("%-6d %-14s %10.1f%% %10.1f%% %+7.1fpt  %s" %
                             (P, q, 100 * mv, 100 * xv, 100 * err, tag))
        lines.append("%-6d %-14s %11s %11.2f   (measured PCG iterations a step; the model uses "
                     "the 1-rank count %.2f)" % (P, "iterations", "", its,
                                                costs["pressure_iterations_per_step"]))
    lines.append("%s at %s ranks: %s" % (name, ",".join(map(str, a.ranks)),
                                         "PASS" if ok_all else "FAIL"))
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "validate-%s.csv" % name), "w") as f:
        f.write("# MODEL VALIDATION (bench/scripts/validate_model.py); load: %s\n" % a.load_note)
        f.write("case,ranks,timer,quantity,model,measured,error,verdict\n")
        for r in rows:
            f.write("%s,%d,%s,%s,%.6g,%.6g,%.6g,%s\n" % tuple(r))
    with open(os.path.join(out_dir, "validate-%s.txt" % name), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out_dir, "validate-costs-%s.json" % name), "w") as f:
        json.dump(costs, f, indent=1)
    print("\n".join(lines), flush=True)
    return ok_all


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=["bench/cases/case2-small.json",
                                                   "bench/cases/case3-small.json"],
                    help="relative to the repository root (runs start there)")
    ap.add_argument("--coloc", default=os.path.join(ROOT, "build/coloc"))
    ap.add_argument("--bench", default=os.path.join(ROOT, "build/bench"))
    ap.add_argument("--pingpong", default=os.path.join(ROOT, "bench/results/model/pingpong.json"))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--ranks", default="2", help="rank counts to predict, e.g. 2,4,8,16 (1 is "
                    "always run: the calibration)")
    ap.add_argument("--steps", type=int, default=0, help="override run.steps (0: the case's)")
    ap.add_argument("--restart", help="every run (1 and 2 ranks, the co-run) continues from this "
                    "checkpoint, e.g. a settled bed (contact_bench.py --settle-only); needs "
                    "--steps (the timed steps) and --settled-steps (the checkpoint's step); one "
                    "case")
    ap.add_argument("--set", action="append", default=[],
                    help="KEY=VALUE for every run and the plan (repeatable)")
    ap.add_argument("--dense-bed", type=float, nargs="?", const=0.01, default=0.0,
                    metavar="OVERLAP", help="the bed starts dense and in contact, no restart "
                    "needed (dense_bed.py; neighbours overlap by OVERLAP of a diameter)")
    ap.add_argument("--settled-steps", type=int, default=0,
                    help="with --restart: the step the checkpoint was written at")
    ap.add_argument("--stream-ranks", type=int, default=0, help="default: every core")
    ap.add_argument("--timer", choices=["busy", "wall"], default="busy")
    ap.add_argument("--overhead-grid", choices=["cubes", "own"], default="cubes",
                    help="hypre's per-level overhead from the cubes or the case's own grid")
    ap.add_argument("--pick", choices=["min", "median"], default="median",
                    help="median: one calibration a 1-rank repeat and the median of each input "
                    "(stream, co-run shares, hypre's overhead, unit costs), the median 2-rank "
                    "run measured; min: the fastest run of each set (least disturbed)")
    ap.add_argument("--no-timer-sync", dest="timer_sync", action="store_false",
                    help="run without run.timer_sync (the wait for the slowest rank is then "
                    "booked to the collective phase that follows it)")
    ap.add_argument("--no-noise", dest="noise", action="store_false",
                    help="neither measure nor model the machine's noise (bench_noise: the "
                    "spread of the cores' speed on the same work, before each repeat's runs)")
    ap.add_argument("--corunner", choices=["stream", "self"], default="stream",
                    help="the co-runner of the memory-share calibration: bench_stream at the "
                    "most contended working set (default), or the same 1-rank run on the other "
                    "core (self)")
    ap.add_argument("--no-pingpong", dest="measure_pingpong", action="store_false",
                    help="take --pingpong instead of measuring it --repeats times")
    ap.add_argument("--runs", default="/tmp/coloc-validate")
    ap.add_argument("--reports", help="take the reports under this folder; run nothing")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench/results/model"))
    ap.add_argument("--strict", action="store_true", help="exit 1 when a 2-rank point fails")
    a = ap.parse_args()
    a.ranks = [int(x) for x in a.ranks.split(",") if int(x) > 1]
    if a.restart and (not a.steps or not a.settled_steps or len(a.cases) != 1):
        ap.error("--restart needs --steps, --settled-steps and one case")
    before = uptime()
    runs = os.path.abspath(a.reports or a.runs)
    a.coloc, a.bench, a.pingpong = (os.path.abspath(x) for x in (a.coloc, a.bench, a.pingpong))
    if not a.reports:
        run_all(a, runs)
        a.load_note = "before: %s; after: %s" % (before, uptime())
        with open(os.path.join(runs, "load.txt"), "w") as f:
            f.write(a.load_note + "\n")
    else:
        note = os.path.join(runs, "load.txt")
        a.load_note = open(note).read().strip() if os.path.exists(note) else "(given reports)"
    ok = all([validate_case(a, runs, c, a.out) for c in a.cases])
    print("validation at %s ranks: %s" % (",".join(map(str, a.ranks)), "PASS" if ok else "FAIL"))
    sys.exit(0 if ok or not a.strict else 1)


if __name__ == "__main__":
    main()

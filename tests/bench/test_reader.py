#!/usr/bin/python3
"""The Python reader (bench/python/coloc: coloc.read_run) and bench/scripts/collect.py on real
runs (issue 49). Runs CASE (tests/robustness/cases/bed.json) on 1 and 2 ranks with fields output,
then checks, against the files read independently (json, csv, h5py):
  - read_run: the report dict, a key path, series.csv as numpy arrays (empty cells NaN), the
    output steps, fields() of the last and of a named step (shapes [nz, ny, nx], attrs), particles()
    (count = report particles.count), a step without output refused naming the steps there;
  - collect.py: one CSV row per run, s_per_step = wall_s / steps, each phase's s_per_step_<phase>
    = timers.<phase>.avg / steps, speedup and efficiency against the 1-rank run, an interrupted
    run left out (and kept with --all), no run -> exit 1.

    test_reader.py COLOC MPIEXEC CASE WORKDIR
CTest: bench_python_reader (labels bench, io)."""
import csv
import json
import math
import os
import shutil
import subprocess
import sys

SRC = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(SRC, "bench", "python"))
import coloc  # noqa: E402

FAILS = []


def check(what, ok):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


def main():
    coloc_bin, mpiexec, case, work = sys.argv[1:5]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    import h5py
    import numpy as np
    runs = {}
    for n in (1, 2):
        out = os.path.join(work, "np%d" % n)
        subprocess.run([mpiexec, "-n", str(n), "--bind-to", "none", coloc_bin, "run", case,
                        "--out", out, "--quiet", "--set", "run.steps=6",
                        "--set", "output.interval_steps=3", "--set", "output.snapshot=false"],
                       check=True, timeout=120)
        runs[n] = out

    run = coloc.read_run(runs[2])
    rep = json.load(open(os.path.join(runs[2], "report.json")))
    check("report is report.json", run.report == rep)
    check("a key path", run["timers.dem_force.max"] == rep["timers"]["dem_force"]["max"]
          and run["mpi.ranks"] == 2 and run.get("no.such.key", 7) == 7)
    try:
        run["run.nothing"]
        check("a missing key raises KeyError", False)
    except KeyError as e:
        check("a missing key raises KeyError naming it", "run.nothing" in str(e))
    with open(os.path.join(runs[2], "series.csv")) as f:
        rows = list(csv.DictReader(f))
    s = run.series
    check("series: every column, one value a row",
          set(s) == set(rows[0]) and all(len(v) == len(rows) for v in s.values()))
    check("series: numbers as in the file",
          all(s["time"][i] == float(r["time"]) for i, r in enumerate(rows)))
    empty = [(k, i) for i, r in enumerate(rows) for k, v in r.items() if v == ""]
    check("series: empty cells are NaN (%d)" % len(empty),
          all(math.isnan(s[k][i]) for k, i in empty))
    check("output steps 0, 3, 6", run.steps == [0, 3, 6] and run.particle_steps == [0, 3, 6])
    f = run.fields()
    cells = rep["config"]["domain"]["cells"]
    with h5py.File(os.path.join(runs[2], "fields_000006.h5")) as h:
        same = all(np.array_equal(f[k], h[k][...]) for k in h)
        attrs_ok = float(h.attrs["time"]) == f.time and f.step == 6
    check("fields(): the last step's datasets and attributes", same and attrs_ok and
          f["p"].shape == (cells[2], cells[1], cells[0]) and f["u"].shape[-1] == 3
          and f.units.get("u") == "m/s")
    f3 = run.fields(3)
    check("fields(3)", f3.step == 3 and f3.time < f.time)
    p = run.particles()
    check("particles(): count = report particles.count",
          len(p["id"]) == rep["particles"]["count"] and p["x"].shape == (len(p["id"]), 3))
    try:
        run.fields(4)
        check("fields(4) (no output there) raises", False)
    except KeyError as e:
        check("fields(4) raises naming the steps there", "0, 3, 6" in str(e))
    try:
        coloc.read_run(work)
        check("a folder without report.json raises", False)
    except FileNotFoundError as e:
        check("a folder without report.json raises naming it", "report.json" in str(e))

    # collect.py: the two runs, and an interrupted one (its report marked so)
    bad = os.path.join(work, "interrupted")
    shutil.copytree(runs[1], bad)
    b = json.load(open(os.path.join(bad, "report.json")))
    b["status"] = "interrupted"
    json.dump(b, open(os.path.join(bad, "report.json"), "w"))
    collect = os.path.join(SRC, "bench", "scripts", "collect.py")
    csv_path = os.path.join(work, "all.csv")
    r = subprocess.run([sys.executable, collect, "--find", work, "--out", csv_path],
                       capture_output=True, text=True)
    print(r.stdout, r.stderr)
    check("collect.py exit 0, the interrupted run named", r.returncode == 0 and
          "skipped %s: status interrupted" % bad in r.stderr)
    table = list(csv.DictReader(open(csv_path)))
    check("collect.py: one row a run", sorted(t["folder"] for t in table) == sorted(runs.values()))
    by = {int(t["ranks"]): t for t in table}
    for n, t in by.items():
        d = json.load(open(os.path.join(runs[n], "report.json")))
        steps = d["run"]["steps"] - d["run"]["first_step"]
        check("np%d: s_per_step = wall_s / steps" % n,
              math.isclose(float(t["s_per_step"]), d["run"]["wall_s"] / steps, rel_tol=1e-12))
        phases = [k for k in d["timers"] if k != "setup"]
        check("np%d: every phase a step, avg and max" % n, all(
            math.isclose(float(t["s_per_step_" + k]), d["timers"][k]["avg"] / steps,
                         rel_tol=1e-12, abs_tol=1e-300) and
            math.isclose(float(t["s_per_step_%s_max" % k]), d["timers"][k]["max"] / steps,
                         rel_tol=1e-12, abs_tol=1e-300) for k in phases))
        check("np%d: provenance columns" % n, t["binding"] == d["provenance"]["mpi_env"]["binding"]
              and t["git_commit"] == d["provenance"]["git_commit"] and t["strategy"] == "uniform")
    s1, s2 = float(by[1]["s_per_step"]), float(by[2]["s_per_step"])
    check("speedup and efficiency against the 1-rank run",
          by[1]["base_ranks"] == by[2]["base_ranks"] == "1" and
          math.isclose(float(by[2]["speedup"]), s1 / s2) and
          math.isclose(float(by[2]["efficiency"]), s1 / s2 / 2) and float(by[1]["speedup"]) == 1)
    r = subprocess.run([sys.executable, collect, runs[1], bad, "--all"], capture_output=True,
                       text=True)
    rows = list(csv.DictReader(r.stdout.splitlines()))
    check("--all keeps the interrupted run (no speedup)", r.returncode == 0 and len(rows) == 2 and
          [x["speedup"] for x in rows if x["status"] == "interrupted"] == [""])
    r = subprocess.run([sys.executable, collect, bad], capture_output=True, text=True)
    check("no run to collect: exit 1", r.returncode == 1 and "no run to collect" in r.stderr)
    r = subprocess.run([sys.executable, collect], capture_output=True, text=True)
    check("no folder given: exit 2", r.returncode == 2)
    if FAILS:
        print("reader: %d check(s) failed" % len(FAILS))
        return 1
    print("reader: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

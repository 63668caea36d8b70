#!/usr/bin/env python3
"""coloc at N simulated ranks (SimGrid SMPI build) gives the particles and fields of the real
serial run (Open MPI build, 1 rank), to 1e-10 relative (docs/smpi.md).

Runs tests/smpi/cases/smpi_bed.json (a tiny coupled bed, particles in contact across block
faces) for a few steps: the reference with `coloc run` on 1 real rank, then the SMPI build at
--ranks simulated ranks with --strategy. Compares series.csv (followed particles' position,
velocity and coupling force each step; the fluid's solid volume and acceleration; bed height,
speeds, contacts, plane-averaged pressure drops and solid fractions), and report.json's fluid
drag force, particle count and checks. Prints "smpi_vs_serial.py: PASS" or the worst values.
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CASE = os.path.join(HERE, "cases", "smpi_bed.json")
RTOL = 1e-10
IDS = "[0,97,333,640,777,1001,1234,1599]"


def run(cmd):
    print("+", " ".join(cmd), flush=True)
    rc = subprocess.call(cmd)
    if rc != 0:
        sys.exit(f"smpi_vs_serial.py: FAIL: exit {rc}")


def close(a, b, scale):
    return abs(a - b) <= RTOL * max(abs(a), abs(b), scale)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reference", required=True, help="coloc of the Open MPI build")
    ap.add_argument("--smpi-build", required=True)
    ap.add_argument("--ranks", type=int, default=64)
    ap.add_argument("--strategy", default="uniform")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--out", required=True)
    ap.add_argument("--compare-only", action="store_true", help="compare the runs already in --out")
    a = ap.parse_args()
    if not a.compare_only:
        shutil.rmtree(a.out, ignore_errors=True)
    common = ["run", CASE, "--quiet", "--set", f"run.steps={a.steps}",
              "--set", f"output.series_particle_ids={IDS}", "--set", "output.diagnostics_interval=1"]
    ref, sim = os.path.join(a.out, "serial"), os.path.join(a.out, f"smpi_np{a.ranks}")
    if not a.compare_only:
        run([a.reference] + common + ["--out", ref])
        run([sys.executable, os.path.join(ROOT, "bench", "scripts", "smpi_run.py"), "--ranks",
             str(a.ranks), "--smpi-build", a.smpi_build, "--real-build",
             os.path.dirname(os.path.abspath(a.reference)), "--"] + common +
            ["--set", f"partition.strategy={a.strategy}", "--out", sim])

    rows_a = list(csv.DictReader(open(os.path.join(ref, "series.csv"))))
    rows_b = list(csv.DictReader(open(os.path.join(sim, "series.csv"))))
    bad, compared = [], 0
    if len(rows_a) != len(rows_b) or len(rows_a) != a.steps:
        bad.append(f"series.csv rows: {len(rows_a)} serial, {len(rows_b)} simulated")
    for ra, rb in zip(rows_a, rows_b):
        if set(ra) != set(rb):
            bad.append("series.csv columns differ")
            break
        done = set()
        for k in ra:
            if k in done or (ra[k] == "" and rb[k] == ""):
                continue
            # A particle's position, velocity and force (pID_x|vx|fx, _y, _z) are compared as
            # vectors: each component to 1e-10 of the vector's magnitude (a force component
            # that nearly cancels is round-off of the others).
            group = [k]
            for axis in ("x", "vx", "fx"):
                if k.endswith("_" + axis):
                    stem = k[: -len(axis)]
                    group = [stem + axis, stem + axis.replace("x", "y"), stem + axis.replace("x", "z")]
            done.update(group)
            va, vb = [float(ra[c]) for c in group], [float(rb[c]) for c in group]
            scale = max(math.sqrt(sum(x * x for x in va)), math.sqrt(sum(y * y for y in vb)))
            for c, x, y in zip(group, va, vb):
                compared += 1
                if not close(x, y, scale):
                    bad.append(f"step {ra['step']} {c}: serial {x!r}, simulated {y!r}")
    rep_a = json.load(open(os.path.join(ref, "report.json")))
    rep_b = json.load(open(os.path.join(sim, "report.json")))
    if rep_b["mpi"]["ranks"] != a.ranks:
        bad.append(f"report.json mpi.ranks {rep_b['mpi']['ranks']}")
    prov = rep_b["provenance"]
    if not (prov["simulated"] is True and prov["mpi_library"].startswith("SMPI")
            and prov["oversubscribed"] is False and prov["cores_used"] == a.ranks):
        bad.append(f"report.json provenance of the simulated run: {prov}")
    # the calibration of the simulation (smpi_run.py): an empty burst's charge at this rank
    # count, a real call's cost from the reference build's bench_mpi_calls, their difference
    cal = prov.get("smpi_calibration", {})
    if not (cal.get("empty_burst_s", 0) > 0 and cal.get("real_call_s", 0) > 0
            and cal.get("iprobe_s", 0) > 0 and cal.get("test_s", 0) > 0 and cal.get("ranks") == a.ranks
            and abs(cal.get("offset_s", -1) - max(0.0, cal["empty_burst_s"] - cal["real_call_s"])) < 1e-12):
        bad.append(f"report.json provenance.smpi_calibration: {cal}")
    if rep_a["provenance"]["simulated"] is not False:
        bad.append("the serial reference says it is simulated")
    if rep_a["particles"]["count"] != rep_b["particles"]["count"]:
        bad.append("particle counts differ")
    for x, y in zip(rep_a["fluid"]["drag_force"], rep_b["fluid"]["drag_force"]):
        compared += 1
        if not close(x, y, 0.0):
            bad.append(f"fluid.drag_force: serial {x!r}, simulated {y!r}")
    contacts = float(rows_a[-1]["contacts_per_particle"] or 0)
    print(f"smpi_vs_serial.py: {a.strategy}, {a.ranks} simulated ranks: {compared} values "
          f"compared, contacts per particle {contacts:.2f}")
    if contacts < 1.0:
        bad.append(f"the bed has {contacts:.2f} contacts a particle (the case must touch)")
    if bad:
        print("\n".join(bad[:20]))
        print("smpi_vs_serial.py: FAIL")
        return 1
    print("smpi_vs_serial.py: PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())

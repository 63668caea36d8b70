#!/usr/bin/env python3
"""Test of bench/scripts/dense_bed.py (CTest: dense_bed_unit, dense_bed_contacts,
smpi_dense_bed_contacts).

    test_dense_bed.py                               # the lattice it computes (no run)
    test_dense_bed.py --run "mpiexec -n 2 build/coloc"        # + a real run in contact
    test_dense_bed.py --smpi-build build-smpi --ranks 4       # + a simulated run in contact

Without options: case3-small's bed becomes 179 x 14 x 100 spheres at 0.99 d that fit the box, the
other keys of the source kept; a size distribution and a bed that does not fit are refused. With
--run / --smpi-build: case3-small with that bed, 1 step: every particle is there and the mean
contacts a particle (report.json bed.contacts_per_particle) is at least 4 (the issue's floor for
timing a bed in contact; a simple-cubic lattice gives 6 inside, fewer on its faces).
Prints "dense_bed: all checks passed" or the failures, exit 1.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import dense_bed  # noqa: E402

CASE = os.path.join(ROOT, "bench", "cases", "case3-small.json")
FAILS = []


def check(what, ok):
    if not ok:
        FAILS.append(what)


def lattice_checks():
    case = dense_bed.load_case(CASE)
    src = dense_bed.dense_source(case, 0.01)[0]
    r = case["particles"]["sources"][0]["radius"]
    check("type lattice", src["type"] == "lattice")
    check(f"counts {src['counts']} == [179, 14, 100]", src["counts"] == [179, 14, 100])
    check("pitch 0.99 d", all(abs(s - 0.99 * 2 * r) < 1e-15 for s in src["spacing"]))
    L = case["domain"]["length"]
    for a in range(3):
        lo = src["lo"][a] - r
        hi = src["lo"][a] + (src["counts"][a] - 1) * src["spacing"][a] + r
        check(f"axis {a}: the lattice [{lo}, {hi}] inside [0, {L[a]}]", lo > 0 and hi < L[a])
    check("at least the source's count",
          src["counts"][0] * src["counts"][1] * src["counts"][2] >= 250000)
    bad = json.loads(json.dumps(case))
    bad["particles"]["sources"][0]["size"] = {"distribution": "uniform", "min": 1e-3, "max": 2e-3}
    try:
        dense_bed.dense_source(bad)
        check("a size distribution is refused", False)
    except ValueError as e:
        check(f"size refusal names it: {e}", "size" in str(e))
    big = json.loads(json.dumps(case))
    big["particles"]["sources"][0]["count"] = 10**6
    try:
        dense_bed.dense_source(big)
        check("a bed taller than its box is refused", False)
    except ValueError as e:
        check(f"height refusal says where: {e}", "along z" in str(e))
    arg = dense_bed.set_argument(CASE)
    check("one --set argument", arg.startswith("particles.sources=[") and " " not in arg)


def run_checks(cmd, out, simulated):
    args = ["run", CASE, "--set", dense_bed.set_argument(CASE), "--set", "run.steps=1",
            "--quiet", "--overwrite", "--out", out]
    p = subprocess.run(cmd + args, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        FAILS.append(f"run failed ({p.returncode}): {p.stdout[-2000:]} {p.stderr[-2000:]}")
        return
    rep = json.load(open(os.path.join(out, "report.json")))
    n = rep["bed"]["particles"]
    cpp = rep["bed"]["contacts_per_particle"]
    print(f"dense_bed: {n} particles, {cpp:.3f} contacts a particle "
          f"(simulated: {rep.get('provenance', {}).get('simulated', False)})")
    check(f"{n} particles == 179 * 14 * 100", n == 179 * 14 * 100)
    check(f"report.json provenance.simulated is {simulated}",
          rep.get("provenance", {}).get("simulated", False) == simulated)
    check(f"contacts a particle {cpp} >= 4", cpp >= 4.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", help="the command that runs coloc, e.g. 'mpiexec -n 2 build/coloc'")
    ap.add_argument("--smpi-build", help="run the SMPI build of this folder instead")
    ap.add_argument("--ranks", type=int, default=4, help="simulated ranks (--smpi-build)")
    a = ap.parse_args()
    lattice_checks()
    with tempfile.TemporaryDirectory() as tmp:
        if a.run:
            run_checks(shlex.split(a.run), os.path.join(tmp, "real"), False)
        if a.smpi_build:
            run_checks([sys.executable, os.path.join(HERE, "smpi_run.py"), "--ranks",
                        str(a.ranks), "--smpi-build", a.smpi_build, "--"],
                       os.path.join(tmp, "smpi"), True)
    if FAILS:
        print("dense_bed: FAILED\n  " + "\n  ".join(FAILS))
        return 1
    print("dense_bed: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

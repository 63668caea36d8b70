#!/usr/bin/python3
"""Unit test of bench/peers/openfoam/openfoam_bench.py without OpenFOAM or coloc (issue 30):
the dictionaries it writes (--write-only) set the solvers as the peers' users run them (icoFoam:
GAMG p relTol 0.05, pFinal relTol 0, 2 PISO correctors; DPMFoam: the Goldschmidt tutorial's
relTol 0.01 / pFinal 0 and 2 correctors), --p-reltol 0 gives back the first comparison's
relTol 0 everywhere, the committed dictionaries are those the script writes now, and the result
tables merge rounds of separate invocations (--append) and summarise min / median / max of the
ratio and of each code's figure. CTest: openfoam_peer_unit (label unit)."""
import argparse
import csv
import filecmp
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import openfoam_bench  # noqa: E402

SCRIPT = os.path.join(HERE, "openfoam_bench.py")
FAILS = []


def check(what, ok):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


def write(what, d, *extra):
    subprocess.run([sys.executable, SCRIPT, what, "--write-only", "--dict-dir", d, *extra],
                   check=True)
    return open(os.path.join(d, "system", "fvSolution")).read()


def solver(text, name):
    """The one-line solver entry `name { ... }` of a generated fvSolution."""
    m = re.search(r"^\s*" + re.escape(name) + r"\s*\{([^}]*)\}", text, re.M)
    return m.group(1) if m else ""


def same_tree(a, b):
    """Same files with the same bytes under a and b (the generated dictionaries)."""
    for root, _, files in os.walk(a):
        for fn in files:
            p = os.path.join(root, fn)
            q = os.path.join(b, os.path.relpath(p, a))
            if not os.path.exists(q) or not filecmp.cmp(p, q, shallow=False):
                return False
    return True


def fake_rows(first, n, peer_s, ours_s, settings):
    rows = []
    for k in range(first, first + n):
        for code, v in (("icoFoam", peer_s[k - first]), ("coloc", ours_s[k - first])):
            rows.append({"code": code, "round": k, "steps": 20, "wall_s_per_step": v,
                         "cpu_s_per_step": v * 0.9, "p_iters_per_step": 6.0,
                         "p_iters_first_step": 20, "p_solves_per_step": 2,
                         "load1_before": "2.5", "load1_after": "2.6",
                         "utc": f"2026-12-05 13:{k:02d}", "settings": settings})
    return rows


def main():
    with tempfile.TemporaryDirectory() as tmp:
        # icoFoam as its users run it (the default)
        ch = write("channel", os.path.join(tmp, "ch"))
        p, pf = solver(ch, "p"), solver(ch, "pFinal")
        check("channel p: GAMG, tolerance 1e-06, relTol 0.05",
              "GAMG" in p and "tolerance 1e-06" in p and "relTol 0.05" in p)
        check("channel pFinal: $p with relTol 0", "$p" in pf and "relTol 0;" in pf)
        check("channel: 2 PISO correctors", re.search(r"nCorrectors\s+2;", ch) is not None)
        check("channel: committed dictionaries are the generated ones",
              same_tree(os.path.join(tmp, "ch"), os.path.join(HERE, "channel")))
        # the first comparison's setting, still reachable
        old = write("channel", os.path.join(tmp, "ch0"), "--p-reltol", "0")
        check("channel --p-reltol 0: p relTol 0", "relTol 0;" in solver(old, "p"))
        one = write("channel", os.path.join(tmp, "ch1"), "--n-correctors", "1")
        check("channel --n-correctors 1", re.search(r"nCorrectors\s+1;", one) is not None)
        # DPMFoam: the Goldschmidt tutorial's solver settings
        fb = write("fbed", os.path.join(tmp, "fb"))
        check("fbed p: relTol 0.01, pFinal relTol 0",
              "relTol 0.01" in solver(fb, "p") and "relTol 0;" in solver(fb, "pFinal"))
        check("fbed: 2 PIMPLE correctors, 1 outer",
              re.search(r"nCorrectors\s+2;", fb) and re.search(r"nOuterCorrectors\s+1;", fb))
        check("fbed: the comment names the tutorial", "Goldschmidt" in fb)
        check("fbed: committed dictionaries are the generated ones",
              same_tree(os.path.join(tmp, "fb"), os.path.join(HERE, "fbed")))
        fb0 = write("fbed", os.path.join(tmp, "fb0"), "--p-reltol", "0", "--n-correctors", "1")
        check("fbed --p-reltol 0 --n-correctors 1: relTol 0, 1 corrector",
              "relTol 0;" in solver(fb0, "p") and re.search(r"nCorrectors\s+1;", fb0))
        # the final momentum solve (PIMPLE's last iteration reads U.airFinal) a complete entry;
        # a macro with a dot ($U.air) is read as a sub-dictionary's entry, and DPMFoam stops
        for text, label in ((fb, "tutorial"), (fb0, "reltol 0")):
            fin = solver(text, "U.airFinal")
            check(f"fbed ({label}): U.airFinal names its solver, relTol 0",
                  "solver smoothSolver;" in fin and "relTol 0;" in fin)
            check(f"fbed ({label}): no macro with a dot in fvSolution",
                  re.search(r"\$[A-Za-z]+\.", text) is None)

        # rounds of two invocations merged (--append), the summary min / median / max
        out = os.path.join(tmp, "res")
        s = "p_reltol=0.05 n_correctors=2 steps=20 dt=0.015 cpu=1"
        args = argparse.Namespace(out=out, append=True)
        rows, first = openfoam_bench.earlier_rows(args, "channel", s)
        check("append to nothing: round 0", rows == [] and first == 0)
        openfoam_bench.write_table(args, "channel", fake_rows(0, 2, [1.5, 1.6], [0.3, 0.4], s),
                                   "icoFoam", "coloc", "s per step", "wall_s_per_step",
                                   "cpu_s_per_step")
        rows, first = openfoam_bench.earlier_rows(args, "channel", s)
        check("append: the next round is 2", first == 2 and len(rows) == 4)
        check("append: numbers read back", rows[0]["wall_s_per_step"] == 1.5)
        rows += fake_rows(first, 1, [1.7], [0.34], s)
        openfoam_bench.write_table(args, "channel", rows, "icoFoam", "coloc", "s per step",
                                   "wall_s_per_step", "cpu_s_per_step")
        with open(os.path.join(out, "channel.csv")) as f:
            check("csv: 6 rows over 3 rounds", len(list(csv.DictReader(f))) == 6)
        md = open(os.path.join(out, "channel.md")).read()
        # ratios 5, 4, 5 -> min 4 / median 5 / max 5; icoFoam 1.5 / 1.6 / 1.7; coloc 0.3/0.34/0.4
        check("md: ratio min / median / max",
              "| ratio icoFoam / coloc | 4 / 5 / 5 |" in md)
        check("md: each code's min / median / max",
              "| icoFoam (s per step) | 1.5 / 1.6 / 1.7 |" in md
              and "| coloc (s per step) | 0.3 / 0.34 / 0.4 |" in md)
        check("md: one line per round with both codes' figures and the start",
              "| 2 | 2026-12-05 13:02 | 1.7 | 0.34 | 5.00x |" in md)
        r = subprocess.run([sys.executable, "-c",
                            "import sys, argparse; sys.path.insert(0, %r); import openfoam_bench;"
                            "openfoam_bench.earlier_rows(argparse.Namespace(out=%r, append=True),"
                            "'channel', 'p_reltol=0 other')" % (HERE, out)],
                           capture_output=True, text=True)
        check("append with other settings: refused", r.returncode != 0
              and "use another --tag" in r.stderr)
    if FAILS:
        sys.exit("openfoam_peer: %d check(s) failed" % len(FAILS))
    print("openfoam_peer: all checks passed")


if __name__ == "__main__":
    main()

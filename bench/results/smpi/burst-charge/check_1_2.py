#!/usr/bin/env python3
"""Real (Open MPI) against simulated (SMPI) runs at 1 and 2 ranks on this machine, the simulation
with SMPI's own burst charge (--burst-charge none) and with the charge of an empty burst
subtracted (measured, smpi_run.py's default): docs/smpi.md, "The charge of an empty burst".

    bench/results/smpi/burst-charge/check_1_2.py OUT [--rounds 3]

Each round runs, back to back, for case2-small (10 steps) and case3-small with its bed in contact
(dense_bed.py, 3 steps), at 1 then 2 ranks: the real run, the simulation without and with the
correction (`run.timer_sync`, uniform). Prints a Markdown table: seconds a step and of the
pressure set-up and solve a step, median (min-max) over the rounds, and each simulation's error
against the real median.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "../../../.."))
sys.path.insert(0, os.path.join(ROOT, "bench", "scripts"))
import dense_bed  # noqa: E402
from mpi_env import mpi_env  # noqa: E402

CASES = {"case2-small": ["--set", "run.steps=10"], "case3-small": ["--set", "run.steps=3"]}


def case_args(case):
    path = os.path.join(ROOT, "bench", "cases", case + ".json")
    extra = list(CASES[case])
    if case == "case3-small":
        extra += ["--set", dense_bed.set_argument(path, 0.01)]
    return [path, "--quiet", "--overwrite", "--set", "run.timer_sync=true"] + extra


def figures(folder):
    rep = json.load(open(os.path.join(folder, "report.json")))
    steps = rep["run"]["steps"]
    t = rep["timers"]
    return {"step": rep["run"]["wall_s"] / steps,
            "setup": t.get("fluid_pressure_assemble", {}).get("max", 0.0) / steps,
            "solve": t.get("fluid_pressure_solve", {}).get("max", 0.0) / steps}


def run(kind, case, ranks, out):
    folder = os.path.join(out, f"{case}-np{ranks}-{kind}")
    args = ["run"] + case_args(case) + ["--out", folder]
    if kind == "real":
        cmd = ["mpirun", "-n", str(ranks), os.path.join(ROOT, "build", "coloc")] + args
        env = mpi_env()
    else:
        cmd = [sys.executable, os.path.join(ROOT, "bench", "scripts", "smpi_run.py"), "--ranks",
               str(ranks), "--burst-charge", "none" if kind == "smpi" else "measured", "--"] + args
        env = None
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        sys.stderr.write(r.stdout + r.stderr)
        sys.exit(f"check_1_2.py: {kind} {case} at {ranks} ranks failed")
    return figures(folder)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    kinds = ["real", "smpi", "smpi-corrected"]
    got = {}
    for r in range(a.rounds):
        for case in CASES:
            for ranks in (1, 2):
                for kind in kinds:
                    f = run(kind, case, ranks, a.out)
                    got.setdefault((case, ranks, kind), []).append(f)
                    print(f"round {r + 1} {case} np{ranks} {kind}: step {f['step']:.4f} s, "
                          f"set-up {1e3 * f['setup']:.2f} ms, solve {1e3 * f['solve']:.2f} ms",
                          flush=True)
    lines = ["| case | ranks | quantity | real | SMPI (its charge) | error | SMPI (empty burst "
             "subtracted) | error |", "|---|---:|---|---|---|---:|---|---:|"]
    for case in CASES:
        for ranks in (1, 2):
            for q in ("step", "setup", "solve"):
                cells = []
                real = statistics.median(x[q] for x in got[(case, ranks, "real")])
                for kind in kinds:
                    v = [x[q] for x in got[(case, ranks, kind)]]
                    cells.append(f"{1e3 * statistics.median(v):.2f} ({1e3 * min(v):.2f}-"
                                 f"{1e3 * max(v):.2f})")
                    if kind != "real":
                        cells.append(f"{100 * (statistics.median(v) / real - 1):+.0f} %")
                lines.append(f"| {case} | {ranks} | {q} (ms) | " + " | ".join(cells) + " |")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text + "\n")


if __name__ == "__main__":
    main()

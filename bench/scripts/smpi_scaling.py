#!/usr/bin/env python3
"""Strong scaling of a case on a simulated cluster (SimGrid SMPI build; docs/smpi.md).

    bench/scripts/smpi_scaling.py bench/cases/case2-small.json --ranks 28,56 \
        --strategies uniform,tiled --platform paper --steps 2 [--set KEY=VALUE ...] [--out DIR]

Runs the SMPI build (bench/scripts/smpi_run.py) once per strategy and rank count and writes
DIR/smpi_scaling.csv and DIR/smpi_scaling.png (default DIR: ./out/<case>-smpi-scaling): the
SIMULATED time per step, speedup against the fewest ranks of the same strategy, the phase shares
(fluid, DEM, coupling, inter-physics, wait) from report.json, and what each simulation cost (wall
time, peak memory). Every time in them is simulated and contention-free (SMPI runs each rank's
bursts alone on this machine's core); the figure says so in its title.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys

import dense_bed

HERE = os.path.dirname(os.path.abspath(__file__))
SHARES = ["fv", "dem", "coupling", "inter_physics", "wait"]


def case_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def run_one(a, strategy, ranks, folder):
    cmd = [sys.executable, os.path.join(HERE, "smpi_run.py"), "--ranks", str(ranks), "--platform",
           a.platform]
    if a.smpi_build:
        cmd += ["--smpi-build", a.smpi_build]
    cmd += ["--", "run", a.case, "--quiet", "--overwrite", "--set", f"run.steps={a.steps}",
            "--set", f"partition.strategy={strategy}", "--out", folder]
    for kv in a.set:
        cmd += ["--set", kv]
    if a.dense_bed:
        cmd += ["--set", dense_bed.set_argument(a.case, a.dense_bed)]
    out = subprocess.run(cmd, capture_output=True, text=True)
    sys.stdout.write(out.stdout)
    sys.stderr.write(out.stderr)
    m = re.search(r"wall ([0-9.]+) s, peak memory ([0-9.]+) MiB, exit (\d+)", out.stdout)
    if out.returncode != 0 or not m:
        sys.exit(f"smpi_scaling.py: {strategy} at {ranks} ranks failed (exit {out.returncode})")
    rep = json.load(open(os.path.join(folder, "report.json")))
    if not rep.get("provenance", {}).get("simulated", False):
        sys.exit(f"smpi_scaling.py: {folder}/report.json is not from a simulated run")
    row = {"strategy": strategy, "ranks": ranks,
           "step_s_simulated": rep["run"]["wall_s"] / rep["run"]["steps"],
           "simulation_wall_s": float(m.group(1)), "simulation_peak_mib": float(m.group(2))}
    for k in SHARES:
        row["share_" + k] = rep["fractions"].get(k, 0.0)
    row["particles"] = rep.get("bed", {}).get("particles", "")
    row["contacts_per_particle"] = rep.get("bed", {}).get("contacts_per_particle", "")
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case")
    ap.add_argument("--ranks", required=True, help="comma-separated, e.g. 28,56,112")
    ap.add_argument("--strategies", default="uniform,balanced,tiled,independent")
    ap.add_argument("--platform", default="paper")
    ap.add_argument("--steps", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE for the case")
    ap.add_argument("--dense-bed", type=float, nargs="?", const=0.01, default=0.0,
                    metavar="OVERLAP", help="the bed starts dense and in contact (dense_bed.py; "
                    "neighbours overlap by OVERLAP of a diameter, default 0.01)")
    ap.add_argument("--smpi-build", help="the SMPI build folder (default: smpi_run.py's)")
    ap.add_argument("--out", help="output folder (default: ./out/<case>-smpi-scaling)")
    a = ap.parse_args()
    ranks = [int(r) for r in a.ranks.split(",")]
    strategies = [s for s in a.strategies.split(",") if s]
    out = a.out or os.path.join("out", case_name(a.case) + "-smpi-scaling")
    os.makedirs(out, exist_ok=True)
    rows = []
    for s in strategies:
        for p in ranks:
            rows.append(run_one(a, s, p, os.path.join(out, f"{s}-np{p}")))
            first = next(r for r in rows if r["strategy"] == s)
            rows[-1]["speedup"] = first["step_s_simulated"] / rows[-1]["step_s_simulated"] * first["ranks"]
    path = os.path.join(out, "smpi_scaling.csv")
    with open(path, "w", newline="") as f:
        f.write(f"# SIMULATED (SimGrid SMPI, platform {a.platform}, contention-free): "
                f"{case_name(a.case)}, {a.steps} steps a run; speedup relative to the fewest "
                f"ranks of each strategy, times that many ranks\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"smpi_scaling.py: wrote {path}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("smpi_scaling.py: no matplotlib, no figure")
        return 0
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for s in strategies:
        rs = [r for r in rows if r["strategy"] == s]
        ax1.plot([r["ranks"] for r in rs], [r["speedup"] for r in rs], "o-", label=s)
        ax2.plot([r["ranks"] for r in rs], [100 * r["share_inter_physics"] for r in rs], "o-",
                 label=s)
    lo, hi = min(ranks), max(ranks)
    ax1.plot([lo, hi], [lo, hi], "k:", label="ideal")
    ax1.set_xlabel("simulated MPI ranks")
    ax1.set_ylabel("speedup (simulated time per step)")
    ax2.set_xlabel("simulated MPI ranks")
    ax2.set_ylabel("inter-physics exchange, % of the step")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"SIMULATED (SimGrid SMPI, {a.platform} cluster, contention-free): "
                 f"{case_name(a.case)}, {a.steps} steps", fontsize=10)
    fig.tight_layout()
    png = os.path.join(out, "smpi_scaling.png")
    fig.savefig(png, dpi=110)
    print(f"smpi_scaling.py: wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

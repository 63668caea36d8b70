#!/usr/bin/python3
"""Benchmark 1 as in the paper's figure: normalised particle velocity and drag force, and
normalised deposited solid volume and L1 norm of the fluid acceleration, against time, for a
serial and a parallel run on the same axes.

    bench/scripts/plot_case1.py out/case1-np1/series.csv out/case1-np2/series.csv \
        --labels SEQ PAR --out bench/results/case1/case1.png [--boundary 0.5]

Each quantity is divided by its maximum over the serial run (the paper's normalisation). The
time at which the particle crosses --boundary (x, m) is marked.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    cols = {k: [float(r[k]) for r in rows] for k in rows[0]}
    cols["speed"] = [(a * a + b * b + c * c) ** 0.5 for a, b, c in zip(cols["p0_vx"], cols["p0_vy"], cols["p0_vz"])]
    cols["force"] = [(a * a + b * b + c * c) ** 0.5 for a, b, c in zip(cols["p0_fx"], cols["p0_fy"], cols["p0_fz"])]
    return cols


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("series", nargs="+")
    p.add_argument("--labels", nargs="+")
    p.add_argument("--out", default="case1.png")
    p.add_argument("--boundary", type=float, default=0.5)
    a = p.parse_args()
    labels = a.labels or [f"run {i}" for i in range(len(a.series))]
    runs = [read(s) for s in a.series]
    ref = runs[0]
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    styles = ["-", "--", ":", "-."]
    panels = ((axes[0], (("speed", "particle velocity"), ("force", "fluid force"))),
              (axes[1], (("solid_volume", "solid volume"), ("fluid_accel_l1", "L1 fluid acceleration"))))
    for ax, quantities in panels:
        for q, name in quantities:
            scale = max(abs(v) for v in ref[q]) or 1.0
            for run, lab, st in zip(runs, labels, styles):
                ax.plot(run["time"], [v / scale for v in run[q]], st, label=f"{name} ({lab})")
        ax.set_ylabel("normalised")
        ax.legend(fontsize=8)
    cross = next((t for t, x in zip(ref["time"], ref["p0_x"]) if x >= a.boundary), None)
    if cross is not None:
        for ax in axes:
            ax.axvline(cross, color="0.5", lw=0.8)
        axes[0].annotate(f"crosses x = {a.boundary} m at {cross:.3f} s", (cross, 0.5), fontsize=8,
                         xytext=(5, 0), textcoords="offset points")
    axes[1].set_xlabel("time (s)")
    axes[0].set_title("Benchmark 1: one particle travelling across a process boundary", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"plot_case1: wrote {a.out}")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Benchmark 1 as in the paper's figure: the particle's speed and the fluid force on it, and
the deposited solid volume and the L1 norm of the fluid acceleration, against time, for a
serial and a parallel run on the same axes; below, the difference of each run from the first.

    bench/scripts/plot_case1.py out/case1-np1/series.csv out/case1-np2/series.csv \
        --labels SEQ PAR --out bench/results/case1/case1.png [--boundary 0.5]

Each quantity is divided by the largest magnitude it reaches in the first (serial) run, the
paper's normalisation; the legend gives that value with its unit. The difference panel shows
|run - first run| / (that same value) on a log axis, step by step; a difference that is exactly 0
at every step is named in the legend (it has no point on a log axis). The time at which the
particle crosses --boundary (x, m) is marked.
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import provenance  # noqa: E402  (bench/scripts/provenance.py: the stamp on every plot)

QUANTITIES = (("speed", "particle speed |v|", "m/s"), ("force", "fluid force |F| on it", "N"),
              ("solid_volume", "deposited solid volume", "m^3"),
              ("fluid_accel_l1", "L1 norm of the fluid acceleration", "m/s^2"))


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    need = ["step", "time", "solid_volume", "fluid_accel_l1", "p0_x"] + \
        [f"p0_{q}{d}" for q in ("v", "f") for d in "xyz"]
    cols = {k: [float(r[k]) for r in rows] for k in need}
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
    fig, axes = plt.subplots(3, 1, figsize=(8, 10), sharex=True,
                             gridspec_kw={"height_ratios": [1, 1, 1]})
    styles = ["-", "--", ":", "-."]
    scales = {q: (max(abs(v) for v in ref[q]) or 1.0) for q, _, _ in QUANTITIES}
    for ax, quantities in ((axes[0], QUANTITIES[:2]), (axes[1], QUANTITIES[2:])):
        for q, name, unit in quantities:
            for run, lab, st in zip(runs, labels, styles):
                ax.plot(run["time"], [v / scales[q] for v in run[q]], st,
                        label=f"{name} / {scales[q]:.3g} {unit} ({lab})")
        ax.set_ylabel(f"value / its max. in the {labels[0]} run (1)")
        ax.legend(fontsize=7)
    ax = axes[2]
    notes = []
    for i, (run, lab) in enumerate(zip(runs[1:], labels[1:])):
        steps = {s: k for k, s in enumerate(ref["step"])}
        for j, (q, name, unit) in enumerate(QUANTITIES):
            t, d = [], []
            for k, s in enumerate(run["step"]):
                if s in steps:
                    t.append(run["time"][k])
                    d.append(abs(run[q][k] - ref[q][steps[s]]) / scales[q])
            if not d or max(d) == 0:
                notes.append(f"{name}: {lab} = {labels[0]} exactly at every step")
                continue
            ax.semilogy([ti for ti, di in zip(t, d) if di > 0], [di for di in d if di > 0],
                        ".", ms=2, color=f"C{j}",
                        label=f"{name} (max {max(d):.2g}; exactly 0 at {d.count(0)} of {len(d)} steps)")
    if notes:
        ax.plot([], [], " ", label="\n".join(notes))
    ax.set_ylabel(f"|{' / '.join(labels[1:])} - {labels[0]}| / max. in {labels[0]} (1)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    cross = next((t for t, x in zip(ref["time"], ref["p0_x"]) if x >= a.boundary), None)
    if cross is not None:
        for ax in axes:
            ax.axvline(cross, color="0.5", lw=0.8)
        axes[0].annotate(f"crosses x = {a.boundary} m at {cross:.3f} s", (cross, 0.5), fontsize=8,
                         xytext=(5, 0), textcoords="offset points")
    axes[2].set_xlabel("time (s)")
    axes[0].set_title("Benchmark 1: one particle travelling across a process boundary", fontsize=10)
    fig.tight_layout()
    # the runs behind the series: each series.csv's report.json beside it (else the file itself)
    reports, files = [], []
    for s in a.series:
        rep = os.path.join(os.path.dirname(os.path.abspath(s)), "report.json")
        if provenance.of_report(rep) is not None:
            reports.append(rep)
        else:
            files.append(s)
    provenance.stamp(fig, reports=reports, data_files=files)
    provenance.savefig(fig, a.out, dpi=120)
    print(f"plot_case1: wrote {a.out}")


if __name__ == "__main__":
    main()

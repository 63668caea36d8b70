#!/usr/bin/python3
"""Compare partition strategies (uniform, balanced, independent, tiled) on one case over rank counts.

    bench/scripts/strategies.py bench/cases/clustered.json --ranks 2 4 8 \
        --out bench/results/strategies-clustered [--set run.steps=20 ...]

Writes strategies.csv (one row per run) and three PNG plots against ranks:
  imbalance.png      load imbalance, max/avg busy (thread CPU) time of the compute phases;
  busy_max.png       modelled step time: the largest busy time over ranks per step;
  inter_physics.png  inter-physics remote bytes per step and the inter-physics share of the step.
--repeat R runs each point R times (line: median, band: min-max); --plot-only re-plots an
existing strategies.csv. Ranks above --cores are shaded "oversubscribed" on every plot; a value
of exactly 0 on a log axis is drawn as a cross at the floor and named in the legend.
Busy time is the thread CPU time of the compute phases (halo, ghost and exchange phases excluded),
so the imbalance is meaningful when ranks outnumber cores (such runs are marked "oversubscribed";
Open MPI is told to yield when idle so that waiting ranks do not burn the cores).
"""
import argparse
import csv
import json
import os
import shlex
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import provenance  # noqa: E402  (bench/scripts/provenance.py: the stamp on every plot)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def layout_name(part, key):
    """'2x1x2' for a process grid, 'N boxes' for a tiled layout (no grid: null dims)."""
    dims = part.get(key)
    if dims is None:
        return "%d boxes" % len(part.get("boxes", []))
    return "x".join(map(str, dims))


def row_of(r, s, n, rep, cores):
    steps = max(r["run"]["steps"], 1)
    ex = r["exchange"]
    wall = max(r["run"]["wall_s"], 1e-300)
    return {
        "strategy": s, "ranks": n, "repeat": rep, "oversubscribed": int(n > cores), "steps": steps,
        "fluid_dims": layout_name(r["partition"], "fluid_dims"),
        "particle_dims": layout_name(r["partition"], "particle_dims"),
        "busy_max_per_step": r["load"]["busy_s_max"] / steps,
        "busy_avg_per_step": r["load"]["busy_s_avg"] / steps,
        "imbalance": r["load"]["imbalance"],
        "wall_per_step": r["run"]["wall_s"] / steps,
        "inter_remote_bytes_per_step": ex["inter_physics_remote"]["bytes"] / steps,
        "inter_remote_messages_per_step": ex["inter_physics_remote"]["messages"] / steps,
        "inter_local_bytes_per_step": ex["inter_physics_local"]["bytes"] / steps,
        "frac_inter_physics": r["fractions"]["inter_physics"],
        # the across-ranks part alone (must be 0 where no byte crossed ranks)
        "frac_inter_remote": r["timers"].get("exchange_remote", {}).get("avg", 0.0) / wall,
        "modelled_imbalance": r["partition"].get(s, {}).get("modelled_imbalance", ""),
    }


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case")
    p.add_argument("--ranks", type=int, nargs="+", default=[2, 4, 8])
    p.add_argument("--strategies", nargs="+", default=["uniform", "balanced", "independent", "tiled"])
    p.add_argument("--repeat", type=int, default=1, help="runs per point (bands: min-max)")
    p.add_argument("--launcher", default="mpiexec -n {n} --bind-to none")
    p.add_argument("--coloc", default=os.path.join(ROOT, "build", "coloc"))
    p.add_argument("--out", required=True)
    p.add_argument("--cores", type=int, default=os.cpu_count() or 1)
    p.add_argument("--plot-only", action="store_true", help="re-plot an existing strategies.csv")
    p.add_argument("--set", nargs="*", default=[], help="key=value overrides for every run")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1")
    path = os.path.join(a.out, "strategies.csv")
    rows = []
    reports = []  # the runs' report.json (their provenance stamps the plots)
    if a.plot_only:
        with open(path) as f:
            for r in csv.DictReader(f):
                row = {}
                for k, v in r.items():
                    try:
                        row[k] = float(v) if k not in ("strategy", "fluid_dims", "particle_dims") else v
                    except ValueError:
                        row[k] = v
                row["ranks"] = int(row["ranks"])
                row["oversubscribed"] = int(row["ranks"] > a.cores)
                rows.append(row)
        a.ranks = sorted({r["ranks"] for r in rows})
        a.strategies = [s for s in a.strategies if any(r["strategy"] == s for r in rows)]
    else:
        for n in a.ranks:
            for s in a.strategies:
                for rep in range(a.repeat):
                    out = os.path.join(a.out, "runs", f"{s}_np{n}" + (f"_r{rep}" if a.repeat > 1 else ""))
                    cmd = shlex.split(a.launcher.format(n=n)) + [a.coloc, "run", a.case, "--quiet", "--overwrite", "--out",
                                                                 out, "--set", f"partition.strategy={s}"]
                    for kv in a.set:
                        cmd += ["--set", kv]
                    print("strategies:", " ".join(cmd), flush=True)
                    subprocess.run(cmd, check=True, env=env)
                    with open(os.path.join(out, "report.json")) as f:
                        reports.append(json.load(f))
                        rows.append(row_of(reports[-1], s, n, rep, a.cores))
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        provenance.write_sidecar(path, reports)  # strategies.csv.provenance.json, for --plot-only
    name = os.path.basename(a.case).replace(".json", "")
    reps = max(int(r.get("repeat", 0) or 0) for r in rows) + 1
    band = f"; bands: min-max of {reps} repeats" if reps > 1 else "; one run per point"

    def plot(key, ylabel, fname, scale=1.0, logy=False):
        fig, ax = plt.subplots(figsize=(6.4, 5.0))
        over = sorted({r["ranks"] for r in rows if r["oversubscribed"]})
        if over:
            ax.axvspan(a.cores + 0.5, max(over) + 0.5, color="0.88", zorder=0,
                       label=f"oversubscribed (> {a.cores} cores)")
        positive = [scale * r[key] for r in rows if isinstance(r.get(key), float) and r[key] > 0]
        floor = (min(positive) if positive else 1.0) / 10 if logy else 0.0
        zeros = False
        for s, st in zip(a.strategies, ("o-", "s--", "^:", "d-.")):
            by = {}
            for r in rows:
                if r["strategy"] == s:
                    by.setdefault(r["ranks"], []).append(scale * r[key])
            ns = sorted(by)
            mid = [sorted(by[n])[len(by[n]) // 2] for n in ns]
            if logy:
                line, = ax.plot([n for n, v in zip(ns, mid) if v > 0], [v for v in mid if v > 0], st, label=s)
                z = [n for n, v in zip(ns, mid) if v == 0]
                if z:
                    zeros = True
                    ax.plot(z, [floor] * len(z), "x", color=line.get_color(), ms=8)
            else:
                line, = ax.plot(ns, mid, st, label=s)
            if reps > 1:
                ax.fill_between(ns, [min(by[n]) for n in ns], [max(by[n]) for n in ns],
                                color=line.get_color(), alpha=0.2, lw=0)
        if zeros:
            ax.plot([], [], "kx", label=f"exactly 0 (drawn at {floor:g})")
        ax.set_xlabel("MPI ranks")
        ax.set_ylabel(ylabel)
        if logy:
            ax.set_yscale("log")
            ax.set_ylim(bottom=floor / 2)
        ax.set_xticks(a.ranks)
        ax.set_title(f"{name}: {ylabel}\n(median of the repeats{band})", fontsize=9)
        ax.legend(fontsize=8)
        fig.tight_layout()
        # the runs (or, re-plotted, strategies.csv and its sidecar) behind the plot
        provenance.stamp(fig, reports=reports, data_files=[] if reports else [path])
        provenance.savefig(fig, os.path.join(a.out, fname), dpi=120)
        plt.close(fig)

    plot("imbalance", "load imbalance: max / mean over ranks of the busy time (1)", "imbalance.png")
    plot("busy_max_per_step", "largest busy (thread CPU) time of a rank per step (ms)", "busy_max.png", 1e3)
    plot("inter_remote_bytes_per_step", "inter-physics bytes sent across ranks per step (B)",
         "inter_physics_bytes.png", 1.0, True)
    plot("frac_inter_physics", "inter-physics exchange wall time / run wall time (%)", "inter_physics.png",
         100.0)
    print(f"strategies: wrote {path} and plots in {a.out}")


if __name__ == "__main__":
    main()

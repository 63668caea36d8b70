#!/usr/bin/python3
"""Strong scaling of a coloc case: run it over rank counts and modes, collect the reports,
write a CSV table and PNG plots.

    bench/scripts/scaling.py bench/cases/case3-small.json --ranks 1 2 4 --repeat 2 \
        --modes coupled fluid particles --coloc build/coloc      # -> out/case3-small-scaling/

On a cluster pass the launcher, e.g. --launcher "srun -n {n}" (default
"mpiexec -n {n} --bind-to none") and --cores (the cores available, for the oversubscription
mark). Overrides go to every run: --set key=value (repeatable), or key=value ... after --.
Points with more ranks than --cores (default: this machine's) are marked "oversubscribed" in
the CSV and shaded on the plots (and run with OMPI_MCA_mpi_yield_when_idle=1 unless the
environment sets it). --plot-only re-plots an existing scaling.csv. Lines are the fastest
repeat, bands the min-max over the repeats; a share of exactly 0 is drawn as a cross at the
floor of the log axis and named in the legend.

Outputs (in --out, default out/<case name>-scaling/ under the current folder, beside the
out/<case name>/ of `coloc run`; the source tree's bench/results/ only when asked for with --out
bench/results/...): scaling.csv (one row per run; per-run
folders under runs/, not committed), speedup.png (each mode's speedup over its smallest rank
count, fastest repeat), shares.png (fluid / particles / coupling arithmetic / inter-physics
shares of each coupled mode's step against ranks), inter_physics.png (the inter-physics exchange
share against ranks as in the paper, split into inside-a-rank and across-ranks parts, with the
paper's 0.1 % and 1 % marks).
"""
import argparse
import csv
import json
import os
import shlex
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

import provenance  # noqa: E402  (bench/scripts/provenance.py: the stamp on every plot)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))  # bench/python, share/coloc/python
import coloc  # noqa: E402  (find_coloc: the installed binary beside this script, or build/coloc)


def run_point(args, n, mode, rep):
    out = os.path.join(args.out, "runs", f"{mode}_np{n}_r{rep}")
    launcher = args.launcher.format(n=n)
    cmd = shlex.split(launcher) + [args.coloc, "run", args.case, "--quiet", "--overwrite", "--out", out,
                                   "--set", f"run.mode={mode}"]
    for s in args.set:
        cmd += ["--set", s]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1",
               # more ranks than cores: waiting ranks yield their core (README, "Containers")
               OMPI_MCA_mpi_yield_when_idle=os.environ.get(
                   "OMPI_MCA_mpi_yield_when_idle", "1" if n > args.cores else "0"),
               OMPI_MCA_btl_vader_single_copy_mechanism=os.environ.get(
                   "OMPI_MCA_btl_vader_single_copy_mechanism", "none"))
    print("scaling:", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, env=env)
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


def row_of(report, n, mode, rep, cores):
    t = report["timers"]
    step = report["run"]["wall_s"] / max(report["run"]["steps"], 1)
    fr = report["fractions"]
    ex = report["exchange"]
    return {
        "mode": mode, "ranks": n, "repeat": rep, "oversubscribed": int(n > cores),
        "steps": report["run"]["steps"], "wall_s": report["run"]["wall_s"], "s_per_step": step,
        "setup_s": report["run"].get("setup_s", 0.0),
        "frac_fv": fr["fv"], "frac_dem": fr["dem"], "frac_coupling": fr["coupling"],
        "frac_inter_physics": fr["inter_physics"],
        "inter_local_bytes": ex["inter_physics_local"]["bytes"],
        "inter_remote_bytes": ex["inter_physics_remote"]["bytes"],
        "inter_remote_messages": ex["inter_physics_remote"]["messages"],
        "intra_bytes": ex["intra_physics"]["bytes"],
        "cell_steps_per_s": report["throughput"]["cell_steps_per_s"],
        "particle_steps_per_s": report["throughput"]["particle_steps_per_s"],
        "peak_rss_bytes_sum": report["memory"]["peak_rss_bytes_sum"],
        "imbalance": report.get("load", {}).get("imbalance", 1.0),
        "exchange_remote_s": t.get("exchange_remote", {}).get("max", 0.0),
        # the two parts of the inter-physics share: inside a rank (co-located) and across ranks
        "frac_inter_local": t.get("exchange_local", {}).get("avg", 0.0) / max(report["run"]["wall_s"], 1e-300),
        "frac_inter_remote": t.get("exchange_remote", {}).get("avg", 0.0) / max(report["run"]["wall_s"], 1e-300),
    }


def best(rows, mode):
    """Per rank count, the fastest repeat (the usual strong-scaling convention)."""
    out = {}
    for r in rows:
        if r["mode"] != mode:
            continue
        n = r["ranks"]
        if n not in out or r["s_per_step"] < out[n]["s_per_step"]:
            out[n] = r
    return [out[n] for n in sorted(out)]


def spread(rows, mode, key):
    """Per rank count (sorted), the min and max of key over the repeats."""
    by = {}
    for r in rows:
        if r["mode"] == mode:
            by.setdefault(r["ranks"], []).append(r[key])
    ns = sorted(by)
    return ns, [min(by[n]) for n in ns], [max(by[n]) for n in ns]


def shares_without_bytes(rows):
    """Rows whose across-ranks inter-physics share is non-zero with no byte sent across ranks."""
    return [r for r in rows if r.get("frac_inter_remote", 0) > 0 and r.get("inter_remote_bytes", 0) == 0]


COUPLED_MODES = (("coupled", "o-"), ("dummy_dem", "d-."))


def shade_oversubscribed(ax, rows, cores):
    """Grey band over the rank counts beyond this machine's cores, named in the legend."""
    over = sorted({r["ranks"] for r in rows if r["oversubscribed"]})
    if not over:
        return
    ax.axvspan(cores + 0.5, max(over) + 0.5, color="0.88", zorder=0,
               label=f"oversubscribed (> {cores} cores)")


def plot(rows, args, cores, reports=()):
    """speedup.png, shares.png, inter_physics.png; stamped with the runs' provenance (reports),
    or, re-plotted, with scaling.csv's (its sidecar, else the commit that last changed it)."""
    csv_path = os.path.join(args.out, "scaling.csv")

    def save(fig, fname):
        provenance.stamp(fig, reports=reports, data_files=[] if reports else [csv_path])
        provenance.savefig(fig, os.path.join(args.out, fname), dpi=120)

    name = os.path.basename(args.case).replace(".json", "")
    reps = max(int(r.get("repeat", 0)) for r in rows) + 1
    band = f"; bands: min-max of {reps} repeats" if reps > 1 else ""
    ns = sorted({r["ranks"] for r in rows})
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for mode, style in (("coupled", "o-"), ("dummy_dem", "d-."), ("fluid", "s--"), ("particles", "^:")):
        pts = best(rows, mode)
        if not pts:
            continue
        base = pts[0]["s_per_step"] * pts[0]["ranks"]
        label = {"fluid": "fluid only (CFD)", "particles": "particles only (DEM)",
                 "dummy_dem": "coupled, DummyDEM"}.get(mode, mode)
        line, = ax.plot([p["ranks"] for p in pts], [base / p["s_per_step"] for p in pts], style,
                        label=label)
        x, lo, hi = spread(rows, mode, "s_per_step")
        ax.fill_between(x, [base / h for h in hi], [base / l for l in lo], color=line.get_color(),
                        alpha=0.2, lw=0)
    ax.plot(ns, ns, "k-", lw=0.5, label="ideal")
    shade_oversubscribed(ax, rows, cores)
    ax.set_xticks(ns)
    ax.set_xlabel("MPI ranks")
    ax.set_ylabel("speedup: (ranks x s/step) at the fewest ranks / s/step")
    ax.set_title(f"{name}: strong scaling (line: fastest repeat{band})", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    save(fig, "speedup.png")
    plt.close(fig)

    present = [(m, st) for m, st in COUPLED_MODES if best(rows, m)]
    if not present:
        return
    fig, axes = plt.subplots(1, len(present), figsize=(6.4 * len(present), 5.2), squeeze=False)
    for ax, (mode, _) in zip(axes[0], present):
        pts = best(rows, mode)
        x = [p["ranks"] for p in pts]
        for key, label, st in (("frac_fv", "fluid", "s--"), ("frac_dem", "particles", "^:"),
                               ("frac_coupling", "coupling arithmetic", "o-"),
                               ("frac_inter_physics", "inter-physics exchange", "d-")):
            line, = ax.plot(x, [100 * p[key] for p in pts], st, label=label)
            xs, lo, hi = spread(rows, mode, key)
            ax.fill_between(xs, [100 * v for v in lo], [100 * v for v in hi], color=line.get_color(),
                            alpha=0.2, lw=0)
        shade_oversubscribed(ax, rows, cores)
        ax.set_xticks(x)
        ax.set_xlabel("MPI ranks")
        ax.set_ylabel(f"phase time / {mode} run wall time (%)")
        ax.set_title(f"{name}, {mode}: time shares, mean over ranks\n(fastest repeat{band})", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3)
    fig.tight_layout()
    save(fig, "shares.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7.2, 6.4))
    positive = [100 * r[k] for r in rows for k in ("frac_inter_physics", "frac_inter_local", "frac_inter_remote")
                if r.get(k, 0) > 0]
    floor = min(positive + [0.1]) / 10
    zeros = False
    for mode, st in present:
        pts = best(rows, mode)
        x = [p["ranks"] for p in pts]
        c = "C0" if mode == "coupled" else "C1"
        for key, ls, what in (("frac_inter_physics", "-", "total"),
                              ("frac_inter_local", ":", "inside a rank (co-located)"),
                              ("frac_inter_remote", "--", "across ranks (reverse halo sum, incl. waiting)")):
            if key not in pts[0]:
                continue
            y = [100 * p[key] for p in pts]
            # a zero cannot sit on a log axis: drawn as a cross on the floor, and said so
            ax.plot([xi for xi, yi in zip(x, y) if yi > 0], [yi for yi in y if yi > 0], st[0] + ls,
                    color=c, mfc="none" if key != "frac_inter_physics" else c, label=f"{mode}: {what}")
            z = [xi for xi, yi in zip(x, y) if yi == 0]
            if z:
                zeros = True
                ax.plot(z, [floor] * len(z), "x", color=c, ms=8)
            xs, lo, hi = spread(rows, mode, key)
            keep = [i for i in range(len(xs)) if lo[i] > 0]
            if len(keep) > 1:
                ax.fill_between([xs[i] for i in keep], [100 * lo[i] for i in keep],
                                [100 * hi[i] for i in keep], color=c, alpha=0.12, lw=0)
    if zeros:
        ax.plot([], [], "kx", label=f"exactly 0 (no time booked; drawn at {floor:g} %)")
    ax.axhline(0.1, color="r", ls="--", lw=0.8, label="0.1 % (paper, case 3)")
    ax.axhline(1.0, color="0.5", ls=":", lw=0.8, label="1 % (paper, case 2)")
    shade_oversubscribed(ax, rows, cores)
    ax.set_yscale("log")
    ax.set_ylim(bottom=floor / 2)
    ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xticks(ns)
    ax.set_xlabel("MPI ranks")
    ax.set_ylabel("inter-physics exchange wall time / run wall time (%)")
    ax.set_title(f"{name}: inter-physics exchange share (fastest repeat{band})", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    fig.tight_layout()
    save(fig, "inter_physics.png")
    plt.close(fig)


def default_out(case):
    """Where a run writes without --out: out/<case name>-scaling under the current folder (as
    `coloc run` writes out/<case name>), never into the source tree's bench/results/."""
    return os.path.join(os.getcwd(), "out", os.path.basename(case).replace(".json", "") + "-scaling")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case")
    p.add_argument("--ranks", type=int, nargs="+", default=[1, os.cpu_count() or 1])
    p.add_argument("--modes", nargs="+", default=["coupled", "fluid", "particles"])
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--launcher", default="mpiexec -n {n} --bind-to none")
    p.add_argument("--coloc", default=coloc.find_coloc() or os.path.join(ROOT, "build", "coloc"),
                   help="the coloc binary (default: the installed one beside this script, else "
                        "build/coloc of the source tree, else coloc on PATH)")
    p.add_argument("--out", default=None)
    p.add_argument("--cores", type=int, default=os.cpu_count() or 1)
    p.add_argument("--plot-only", action="store_true", help="re-plot an existing scaling.csv")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override passed to every run (repeatable); also accepted after --")
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:  # everything after -- is KEY=VALUE overrides
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    args = p.parse_args(argv)
    args.set += extra
    if args.out is None:
        args.out = default_out(args.case)
    os.makedirs(args.out, exist_ok=True)
    csv_path = os.path.join(args.out, "scaling.csv")
    rows = []
    reports = []
    if args.plot_only:
        with open(csv_path) as f:
            for r in csv.DictReader(f):
                rows.append({k: (v if k == "mode" else float(v)) for k, v in r.items()})
                rows[-1]["ranks"] = int(rows[-1]["ranks"])
                rows[-1]["oversubscribed"] = int(rows[-1]["ranks"] > args.cores)
    else:
        for n in args.ranks:
            for mode in args.modes:
                for rep in range(args.repeat):
                    reports.append(run_point(args, n, mode, rep))
                    rows.append(row_of(reports[-1], n, mode, rep, args.cores))
        with open(csv_path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        provenance.write_sidecar(csv_path, reports)  # scaling.csv.provenance.json, for --plot-only
    bad = shares_without_bytes(rows)
    if bad:
        print("scaling: warning: an across-ranks share without bytes in", len(bad), "rows, e.g.",
              bad[0], file=sys.stderr)
    plot(rows, args, args.cores, reports)
    print(f"scaling: wrote {csv_path} and plots in {args.out}")


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Pressure-solver options on a case, measured in alternating rounds (docs/fv.md).

    bench/scripts/pressure_options.py [--case bench/cases/fluid-channel.json] [--steps 12]
        [--rounds 3] [--ranks 1] [--coloc build/coloc] [--taskset CPU] [--out DIR] [--reuse]
        NAME=KEY=VALUE[,KEY=VALUE...] ...

Each variant is a list of --set overrides (NAME=base: none). Every round runs every variant
once, in the same order (A, B, C, A, B, C, ...), so that a load change on a shared machine hits
all of them alike. Per variant: PCG (or cycle) iterations per step, pressure-solve seconds per
step, fluid seconds per step (the fluid_* phases, the first step's multigrid set-up
included), each as the median over the rounds with min-max, and the ratio of the medians to
the first variant's, taken per round (same load) with median and min-max.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

FLUID = ["fluid_momentum", "fluid_boundary", "fluid_halo", "fluid_pressure_assemble",
         "fluid_pressure_solve", "fluid_project"]


def run(args, name, sets, rnd):
    out = os.path.join(args.out, f"{name}-r{rnd}")
    cmd = []
    if args.ranks > 1:
        cmd += ["mpirun", "-n", str(args.ranks), "--bind-to", "none"]
    elif args.taskset is not None:
        cmd += ["taskset", "-c", str(args.taskset)]
    cmd += [args.coloc, "run", args.case, "--set", f"run.steps={args.steps}", "--set",
            "run.progress_interval_s=0", "--set", "output.snapshot=false", "--overwrite", "--out", out]
    for s in sets:
        cmd += ["--set", s]
    if args.reuse and os.path.exists(os.path.join(out, "report.json")):
        pass  # summarize an earlier measurement again
    elif subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode:
        return None  # e.g. a smoother that diverges: the run stops with status 3
    r = json.load(open(os.path.join(out, "report.json")))
    t = r["timers"]
    steps = r["run"]["steps"]
    return {
        "its": r["pressure"]["iterations_avg"],
        "solve": t["fluid_pressure_solve"]["max"] / steps,
        "solve_cpu": t["fluid_pressure_solve"]["busy_max"] / steps,
        "fluid": sum(t[p]["max"] for p in FLUID if p in t) / steps,
        "fluid_cpu": sum(t[p]["busy_max"] for p in FLUID if p in t) / steps,
        "res": r["pressure"]["residual_last"],
        "time": r["fluid"]["time"] if "time" in r["fluid"] else r["run"]["sim_time"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default="bench/cases/fluid-channel.json")
    ap.add_argument("--steps", type=int, default=12)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--coloc", default="build/coloc")
    ap.add_argument("--taskset", default=None)
    ap.add_argument("--out", default="out/pressure-options")
    ap.add_argument("--reuse", action="store_true",
                    help="read the reports already in --out instead of running again")
    ap.add_argument("variants", nargs="+")
    args = ap.parse_args()
    variants = []
    for v in args.variants:
        name, _, rest = v.partition("=")
        sets = [] if name == "base" and not rest else [s for s in rest.split(",") if s]
        variants.append((name, sets))
    res = {n: [] for n, _ in variants}
    failed = set()
    for rnd in range(args.rounds):
        for name, sets in variants:
            if name in failed:
                continue
            m = run(args, name, sets, rnd)
            if m is None:
                print(f"round {rnd} {name:28s} FAILED", file=sys.stderr, flush=True)
                failed.add(name)
                continue
            res[name].append(m)
            print(f"round {rnd} {name:28s} its {m['its']:.2f} solve {m['solve']:.4f} s "
                  f"fluid {m['fluid']:.4f} s", file=sys.stderr, flush=True)

    def med(name, key):
        xs = [m[key] for m in res[name]]
        return statistics.median(xs), min(xs), max(xs)

    summarize(variants, res, failed)


def summarize(variants, res, failed):
    """Medians (min-max) over the rounds; ratios to the first variant taken within each round
    (the same load), median (min-max). CPU: the phases' busy time (thread CPU seconds)."""
    base = variants[0][0]

    def stat(xs):
        return f"{statistics.median(xs):.4f} ({min(xs):.4f}-{max(xs):.4f})"

    def ratio(name, key):
        rs = [a[key] / b[key] for a, b in zip(res[name], res[base])]
        return f"{statistics.median(rs):.3f} ({min(rs):.3f}-{max(rs):.3f})" if rs else "-"

    print("| variant | its/step | solve CPU s/step | fluid CPU s/step | solve wall s/step | "
          "fluid wall s/step | solve CPU ratio | fluid CPU ratio | fluid wall ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, _ in variants:
        if name in failed or not res[name]:
            print(f"| {name} | failed | | | | | | | |")
            continue
        col = lambda k: [m[k] for m in res[name]]
        print(f"| {name} | {statistics.median(col('its')):.2f} | {stat(col('solve_cpu'))} | "
              f"{stat(col('fluid_cpu'))} | {stat(col('solve'))} | {stat(col('fluid'))} | "
              f"{ratio(name, 'solve_cpu')} | {ratio(name, 'fluid_cpu')} | {ratio(name, 'fluid')} |")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""A coupled case timed while its bed is in contact: a settling phase run once and written as a
checkpoint, then the timed steps restarted from it at each rank count.

    bench/scripts/contact_bench.py bench/cases/case3-small.json --settle-steps 200 --steps 10 \
        --ranks 1 2 --repeat 2 --coloc build/coloc      # -> bench/results/case3-contact/

Why: the layered source puts the particles a gap apart, so the first steps of a case (all that a
benchmark of a few steps runs) time a bed without contacts. The settling run (1 rank, the case as
it is, `--settle-steps` steps) writes `<work>/settled.h5` once (kept and reused unless
--resettle); every timed run restarts from it (`--restart`, any rank count: the checkpoint is
read on any decomposition) and runs `--steps` more steps. The timers of a restarted run cover its
own steps only (docs/output.md).

Outputs in --out (default bench/results/<case name>-contact/): contact.csv (one row per timed
run: ranks, s/step, fractions fv / dem / coupling / inter_physics / wait, coupling arithmetic in
ns per particle per coupling step, coordination number, load average before the run) and
summary.md (fastest repeat per rank count beside the paper's 92 / < 8 / < 0.1 %). Run folders
and the checkpoint go to --work (default out/<case name>-contact/, not committed).
The coordination number is the mean of series.csv's contacts_per_particle over the timed window
(output.diagnostics_interval = steps / 5 in the timed runs; the diagnostics are booked to
`output`).
"""
import argparse
import csv
import json
import os
import shlex
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpi_env import mpi_env  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
PAPER = "92 / < 8 / < 0.1"  # case 3: DEM / fluid + coupling / inter-physics, % of the step


def env():
    return mpi_env()


def run(args, n, extra, out):
    cmd = shlex.split(args.launcher.format(n=n)) + [args.coloc, "run", args.case, "--quiet",
                                                    "--overwrite", "--out", out] + extra
    for s in args.set:
        cmd += ["--set", s]
    print("contact_bench:", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, env=env())
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


def coordination(series):
    vals = []
    with open(series) as f:
        for row in csv.DictReader(f):
            if row.get("contacts_per_particle"):
                vals.append(float(row["contacts_per_particle"]))
    return (sum(vals) / len(vals), min(vals)) if vals else (float("nan"), float("nan"))


def row_of(rep, n, r, out, load):
    t, fr, run_ = r["timers"], r["fractions"], r["run"]
    steps = run_["steps"] - run_.get("first_step", 0)
    particles = r["particles"]["count"]
    coupling = sum(t[k]["avg"] for k in ("coupling_deposit", "coupling_interpolate",
                                          "coupling_drag") if k in t)
    busy = sum(t[k].get("busy_avg", t[k]["avg"]) for k in (
        "coupling_deposit", "coupling_interpolate", "coupling_drag") if k in t)
    cn_mean, cn_min = coordination(os.path.join(out, "series.csv"))
    # Thread-CPU time by category (busy_avg): on a machine shared with other jobs the wall
    # times of the phases include the time a rank waits for a core, the busy times do not.
    cats = {"fv": "fluid_", "dem": "dem_", "coupling": "coupling_", "inter_physics": "exchange_",
            "wait": "sync"}
    busy_of = {c: sum(v.get("busy_avg", 0.0) for k, v in t.items()
                      if isinstance(v, dict) and k.startswith(p)) for c, p in cats.items()}
    busy_all = sum(busy_of.values()) or 1.0
    return {
        "ranks": n, "repeat": rep, "steps": steps, "particles": particles,
        "s_per_step": run_["wall_s"] / steps,
        "frac_fv": fr["fv"], "frac_dem": fr["dem"], "frac_coupling": fr["coupling"],
        "frac_inter_physics": fr["inter_physics"], "frac_wait": fr.get("wait", 0.0),
        "frac_output": fr.get("output", 0.0),
        # what bench/scripts/check_shares.py (CTest, label bench) holds the share against
        "inter_remote_bytes": r["exchange"]["inter_physics_remote"]["bytes"],
        "inter_local_bytes": r["exchange"]["inter_physics_local"]["bytes"],
        # per particle per coupling step: the ranks' time summed over the particles
        "coupling_ns_per_particle": coupling * n / (particles * steps) * 1e9,
        "coupling_busy_ns_per_particle": busy * n / (particles * steps) * 1e9,
        "coordination_mean": cn_mean, "coordination_min": cn_min,
        "busy_s_per_step": busy_all / steps,
        **{f"busy_{c}": v / busy_all for c, v in busy_of.items()},
        "load_before": load,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case")
    ap.add_argument("--settle-steps", type=int, default=200)
    ap.add_argument("--steps", type=int, default=10, help="timed steps after the settling")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--coloc", default=os.path.join(ROOT, "build", "coloc"))
    ap.add_argument("--launcher", default="mpiexec -n {n} --bind-to none")
    ap.add_argument("--out")
    ap.add_argument("--work")
    ap.add_argument("--resettle", action="store_true")
    ap.add_argument("--settle-only", action="store_true", help="write the checkpoint and stop")
    ap.add_argument("--set", action="append", default=[])
    args = ap.parse_args()
    name = os.path.splitext(os.path.basename(args.case))[0]
    args.out = args.out or os.path.join(ROOT, "bench", "results", f"{name}-contact")
    args.work = args.work or os.path.join(ROOT, "out", f"{name}-contact")
    os.makedirs(args.out, exist_ok=True)
    os.makedirs(args.work, exist_ok=True)

    ck = os.path.join(args.work, "settled.h5")
    if args.resettle or not os.path.exists(ck):
        s = args.settle_steps
        run(args, 1, ["--set", f"run.steps={s}", "--set", f"output.checkpoint_interval={s}",
                      "--set", 'output.checkpoint_file="settled.h5"',
                      "--set", f"output.diagnostics_interval={max(1, s // 20)}"], args.work)
    if args.settle_only:
        return
    total = args.settle_steps + args.steps
    rows = []
    for rep in range(args.repeat):
        for n in args.ranks:  # rank counts alternate, back to back
            out = os.path.join(args.work, f"np{n}_r{rep}")
            load = os.getloadavg()[0]
            r = run(args, n, ["--restart", ck, "--set", f"run.steps={total}",
                              "--set", f"output.diagnostics_interval={max(1, args.steps // 5)}"],
                    out)
            rows.append(row_of(rep, n, r, out, load))
    with open(os.path.join(args.out, "contact.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    best = {}
    for row in rows:
        if row["ranks"] not in best or row["s_per_step"] < best[row["ranks"]]["s_per_step"]:
            best[row["ranks"]] = row
    lines = [f"# {name}: timed with the bed in contact", "",
             f"Settled {args.settle_steps} steps (1 rank), then {args.steps} timed steps "
             f"restarted from the checkpoint; fastest of {args.repeat} repeat(s).", "",
             "Wall clock (`fractions`: phase wall time / run wall time, mean over ranks):", "",
             "| ranks | s/step | DEM % | fluid % | coupling % | inter-physics % | wait % | "
             "coupling ns/particle/step | coordination (mean, min) | load before |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for n in sorted(best):
        b = best[n]
        lines.append(
            f"| {n} | {b['s_per_step']:.4f} | {100 * b['frac_dem']:.1f} | "
            f"{100 * b['frac_fv']:.1f} | {100 * b['frac_coupling']:.1f} | "
            f"{100 * b['frac_inter_physics']:.4f} | "
            f"{100 * b['frac_wait']:.1f} | {b['coupling_ns_per_particle']:.0f} | "
            f"{b['coordination_mean']:.2f}, {b['coordination_min']:.2f} | "
            f"{b['load_before']:.1f} |")
    lines += ["", "Thread-CPU time (`busy_avg` of the phases; shares of the busy time of the "
              "fluid, DEM, coupling, exchange and sync phases):", "",
              "| ranks | busy s/step | DEM % | fluid % | coupling % | inter-physics % | wait % | "
              "coupling ns/particle/step (busy) |", "|---|---|---|---|---|---|---|---|"]
    for n in sorted(best):
        b = best[n]
        lines.append(
            f"| {n} | {b['busy_s_per_step']:.4f} | {100 * b['busy_dem']:.1f} | "
            f"{100 * b['busy_fv']:.1f} | {100 * b['busy_coupling']:.1f} | "
            f"{100 * b['busy_inter_physics']:.4f} | {100 * b['busy_wait']:.1f} | "
            f"{b['coupling_busy_ns_per_particle']:.0f} |")
    lines += ["", f"Paper (case 3, DEM / fluid + coupling / inter-physics): {PAPER} %."]
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

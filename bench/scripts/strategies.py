#!/usr/bin/python3
"""Compare partition strategies (uniform, balanced, independent) on one case over rank counts.

    bench/scripts/strategies.py bench/cases/clustered.json --ranks 2 4 8 \
        --out bench/results/strategies-clustered [--set run.steps=20 ...]

Writes strategies.csv (one row per run) and three PNG plots against ranks:
  imbalance.png      load imbalance, max/avg busy (thread CPU) time of the compute phases;
  busy_max.png       modelled step time: the largest busy time over ranks per step;
  inter_physics.png  inter-physics remote bytes per step and the inter-physics share of the step.
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

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case")
    p.add_argument("--ranks", type=int, nargs="+", default=[2, 4, 8])
    p.add_argument("--strategies", nargs="+", default=["uniform", "balanced", "independent"])
    p.add_argument("--launcher", default="mpiexec -n {n} --bind-to none")
    p.add_argument("--coloc", default=os.path.join(ROOT, "build", "coloc"))
    p.add_argument("--out", required=True)
    p.add_argument("--cores", type=int, default=os.cpu_count() or 1)
    p.add_argument("--set", nargs="*", default=[], help="key=value overrides for every run")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1")
    rows = []
    for n in a.ranks:
        for s in a.strategies:
            out = os.path.join(a.out, "runs", f"{s}_np{n}")
            cmd = shlex.split(a.launcher.format(n=n)) + [a.coloc, "run", a.case, "--quiet", "--out", out,
                                                         "--set", f"partition.strategy={s}"]
            for kv in a.set:
                cmd += ["--set", kv]
            print("strategies:", " ".join(cmd), flush=True)
            subprocess.run(cmd, check=True, env=env)
            with open(os.path.join(out, "report.json")) as f:
                r = json.load(f)
            steps = max(r["run"]["steps"], 1)
            ex = r["exchange"]
            rows.append({
                "strategy": s, "ranks": n, "oversubscribed": int(n > a.cores), "steps": steps,
                "fluid_dims": "x".join(map(str, r["partition"]["fluid_dims"])),
                "particle_dims": "x".join(map(str, r["partition"]["particle_dims"])),
                "busy_max_per_step": r["load"]["busy_s_max"] / steps,
                "busy_avg_per_step": r["load"]["busy_s_avg"] / steps,
                "imbalance": r["load"]["imbalance"],
                "wall_per_step": r["run"]["wall_s"] / steps,
                "inter_remote_bytes_per_step": ex["inter_physics_remote"]["bytes"] / steps,
                "inter_remote_messages_per_step": ex["inter_physics_remote"]["messages"] / steps,
                "inter_local_bytes_per_step": ex["inter_physics_local"]["bytes"] / steps,
                "frac_inter_physics": r["fractions"]["inter_physics"],
                "modelled_imbalance": r["partition"].get("balanced", {}).get("modelled_imbalance", ""),
            })
    path = os.path.join(a.out, "strategies.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    name = os.path.basename(a.case).replace(".json", "")
    over = [n for n in a.ranks if n > a.cores]
    note = f"\n(ranks > {a.cores} oversubscribed on this {a.cores}-core machine)" if over else ""

    def plot(key, ylabel, fname, scale=1.0, logy=False):
        fig, ax = plt.subplots(figsize=(6, 4.5))
        for s, st in zip(a.strategies, ("o-", "s--", "^:")):
            pts = [r for r in rows if r["strategy"] == s]
            ax.plot([r["ranks"] for r in pts], [scale * r[key] for r in pts], st, label=s)
        ax.set_xlabel("MPI ranks")
        ax.set_ylabel(ylabel)
        if logy:
            ax.set_yscale("log")
        ax.set_xticks(a.ranks)
        ax.set_title(f"{name}: {ylabel}{note}", fontsize=9)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, fname), dpi=120)

    plot("imbalance", "load imbalance (max/avg busy time)", "imbalance.png")
    plot("busy_max_per_step", "max busy time per step (ms)", "busy_max.png", 1e3)
    plot("inter_remote_bytes_per_step", "inter-physics remote bytes per step", "inter_physics_bytes.png", 1.0, True)
    plot("frac_inter_physics", "inter-physics share of the step (%)", "inter_physics.png", 100.0)
    print(f"strategies: wrote {path} and plots in {a.out}")


if __name__ == "__main__":
    main()

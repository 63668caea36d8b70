#!/usr/bin/env python3
"""The table of run.sh: for each case and rank count, the real and simulated pressure set-up (a
set-up: fluid_pressure_setup, slowest rank, / set-ups), pressure solve and whole step (a step),
median (min-max) over the rounds, and simulated / real of the medians; then every phase's
simulated / real (slowest rank, medians), the phases that make no MPI call among them
(fluid_project, fluid_boundary, coupling_drag, dem_integrate): what the simulation charges
computation alone.

    compare.py OUT
"""
import glob
import json
import os
import re
import statistics
import sys


def figures(path):
    r = json.load(open(path))
    t, n = r["timers"], r["run"]["steps"]
    setups = max(1, r.get("pressure", {}).get("setups", 1))
    return {"setup": t.get("fluid_pressure_setup", {}).get("max", 0.0) / setups,
            "solve": t["fluid_pressure_solve"]["max"] / n, "step": r["run"]["wall_s"] / n}


def main():
    out = sys.argv[1]
    runs = {}
    for p in glob.glob(os.path.join(out, "*-np*-*-*", "report.json")):
        m = re.match(r"(.+)-np(\d+)-(real|sim)-(\d+)$", os.path.basename(os.path.dirname(p)))
        if m:
            kinds = runs.setdefault((m.group(1), int(m.group(2))), {})
            kinds.setdefault(m.group(3), []).append(figures(p))
            kinds.setdefault(m.group(3) + "_timers", []).append(json.load(open(p))["timers"])
    print("| case | ranks | quantity | real, ms: median (min-max) | simulated, ms | simulated / real |")
    print("|---|---|---|---|---|---|")
    for (case, np), kinds in sorted(runs.items()):
        for q in ("setup", "solve", "step"):
            cells, med = [], {}
            for k in ("real", "sim"):
                v = [1e3 * f[q] for f in kinds.get(k, [])]
                if not v:
                    cells.append("-")
                    continue
                med[k] = statistics.median(v)
                cells.append(f"{med[k]:.3f} ({min(v):.3f}-{max(v):.3f}), {len(v)} runs")
            ratio = f"{med['sim'] / med['real']:.3f}" if len(med) == 2 and med["real"] > 0 else "-"
            what = {"setup": "pressure set-up (a set-up)", "solve": "pressure solve (a step)",
                    "step": "whole step"}[q]
            print(f"| {case} | {np} | {what} | {cells[0]} | {cells[1]} | {ratio} |")
    phases = ("fluid_momentum", "fluid_boundary", "fluid_project", "fluid_halo",
              "fluid_pressure_assemble", "fluid_pressure_setup", "fluid_pressure_solve",
              "coupling_drag", "coupling_interpolate", "dem_force", "dem_integrate")
    print()
    print("simulated / real of each phase (slowest rank, medians over the rounds):")
    print()
    print("| case | ranks | " + " | ".join(phases) + " |")
    print("|---|---|" + "---|" * len(phases))
    for (case, np), kinds in sorted(runs.items()):
        row = []
        for ph in phases:
            med = {}
            for k in ("real", "sim"):
                v = [t[ph]["max"] for t in kinds.get(k + "_timers", []) if ph in t]
                if v:
                    med[k] = statistics.median(v)
            row.append(f"{med['sim'] / med['real']:.2f}" if len(med) == 2 and med["real"] > 0
                       else "-")
        print(f"| {case} | {np} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()

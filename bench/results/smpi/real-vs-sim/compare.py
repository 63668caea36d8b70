#!/usr/bin/env python3
"""The table of run.sh: for each case and rank count, the real and simulated pressure set-up (a
set-up: fluid_pressure_setup, slowest rank, / set-ups), pressure solve and whole step (a step),
median (min-max) over the rounds, and simulated / real of the medians.

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
            runs.setdefault((m.group(1), int(m.group(2))), {}).setdefault(m.group(3), []).append(
                figures(p))
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


if __name__ == "__main__":
    main()

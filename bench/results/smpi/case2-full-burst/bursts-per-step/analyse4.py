#!/usr/bin/python3
"""The bursts SMPI charged during the timed steps of run.sh's simulations, a rank a step.

    analyse4.py [DIR] 56 112 168 280   -> the markdown table (table.md)

The steps are the last run.wall_s seconds of simulated time of each series (tP.ts, 1 ms slots:
count and corrected charge of the bursts under 10 us, 10 us to 1 ms, over 1 ms); divided by the
ranks and the steps. SimGrid's own wall timer (one value over 1 s) was left out by hist4.c."""
import json
import os
import sys

args = sys.argv[1:]
d = args.pop(0) if args and not args[0].isdigit() else os.path.dirname(os.path.abspath(__file__))
print("| ranks | step (s) | set-up / solve a step (s) | bursts a rank a step | charged a rank a step (s) "
      "| < 10 us: bursts / s | 10 us - 1 ms | > 1 ms |")
print("|---:|---:|---|---:|---:|---|---|---|")
for P in map(int, args):
    rows = [list(map(float, l.split())) for l in open(os.path.join(d, f"t{P}.ts"))
            if not l.startswith("#")]
    r = json.load(open(os.path.join(d, f"t{P}-report.json")))
    n, w, t = r["run"]["steps"], r["run"]["wall_s"], r["timers"]
    end = rows[-1][0] + 1e-3
    sel = [x for x in rows if x[0] >= end - w - 1e-3]
    cnt = [sum(x[1 + 2 * c] for x in sel) / P / n for c in range(3)]
    chg = [sum(x[2 + 2 * c] for x in sel) / P / n for c in range(3)]
    cl = " | ".join(f"{cnt[c]:,.0f} / {chg[c]:.4f}" for c in range(3))
    print(f"| {P} | {w / n:.3f} | {t['fluid_pressure_assemble']['max'] / n:.3f} / "
          f"{t['fluid_pressure_solve']['max'] / n:.3f} | {sum(cnt):,.0f} | {sum(chg):.4f} | {cl} |")

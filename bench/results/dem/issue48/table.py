#!/usr/bin/python3
"""The rounds table of docs/benchmarks.md, "DEM force pass, round four", from rounds.csv.

  table.py [rounds.csv]

One row a round (UTC start, load, every code's million particle-steps per CPU second), then
min / median / max over the rounds of each rate, of ns a particle-step and of each coloc code's
ratio to LAMMPS in the same round.
"""
import csv
import os
import statistics
import sys

path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "rounds.csv")
rows = list(csv.DictReader(open(path)))
codes = list(dict.fromkeys(r["code"] for r in rows))
rounds = {}
for r in rows:
    rounds.setdefault((r["utc"], r["round"]), {})[r["code"]] = r
print("| round (UTC) | load | " + " | ".join(codes) + " | new: ns a particle-step | new / lammps |")
print("|---|---:|" + "---:|" * len(codes) + "---:|---:|")
series = {c: [] for c in codes}
ratios = {c: [] for c in codes}
for (utc, _), rs in sorted(rounds.items()):
    vals = [float(rs[c]["cpu_M"]) for c in codes]
    for c, v in zip(codes, vals):
        series[c].append(v)
        ratios[c].append(v / float(rs["lammps"]["cpu_M"]))
    new = float(rs["coloc new"]["cpu_M"])
    print(f"| {utc} | {float(rs[codes[0]]['load1']):.1f} | " + " | ".join(f"{v:.2f}" for v in vals) +
          f" | {1e3 / new:.0f} | {new / float(rs['lammps']['cpu_M']):.2f}x |")
mmm = lambda xs, f=".2f": f"{min(xs):{f}} / {statistics.median(xs):{f}} / {max(xs):{f}}"
print(f"| **min / median / max** ({len(rounds)} rounds) | | " +
      " | ".join(mmm(series[c]) for c in codes) +
      f" | {mmm([1e3 / v for v in series['coloc new']], '.0f')} | {mmm(ratios['coloc new'])} |")
print()
for c in codes:
    if c == "lammps":
        continue
    ns = [1e3 / v for v in series[c]]
    print(f"- {c}: {mmm(series[c])} M particle-steps per CPU second, {min(ns):.0f} / "
          f"{statistics.median(ns):.0f} / {max(ns):.0f} ns a particle-step (worst {max(ns):.0f}), "
          f"{mmm(ratios[c])}x LAMMPS")

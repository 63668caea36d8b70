#!/usr/bin/python3
"""A markdown table of an smpi_scaling.csv (docs/smpi.md, "The paper's figures, executed"):
one row a point, simulated seconds a step.

    table.py CSV

step: as run (its one set-up a run of a few steps included); amortized: with a long run's
set-ups (one every fluid.pressure.setup_interval steps); set-up: one hypre set-up (slowest rank);
DEM, fluid (amortized): rank averages of their phases; model: model.py with a long run's set-ups
and its error against the amortized step; speed-ups over the fewest ranks of the strategy, times
that many (coupled step amortized / fluid amortized / DEM); the simulation's wall time and peak
memory on this machine.
"""
import csv
import sys


def f(x, fmt):
    try:
        return format(float(x), fmt)
    except (TypeError, ValueError):
        return "-"


rows = list(csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith("#")))
print("| strategy | ranks | step | amortized | set-up | DEM | fluid (amort.) | inter-physics % "
      "| model (amort.) | model error | speed-up: step / fluid / DEM | wall | memory |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|")
for r in sorted(rows, key=lambda r: (r["strategy"], int(r["ranks"]))):
    err = r.get("model_error_amortized", "")
    print(f"| {r['strategy']} | {r['ranks']} | {f(r['step_s_simulated'], '.4f')} "
          f"| {f(r['step_s_amortized'], '.4f')} | {f(r['pressure_setup_each_s'], '.4f')} "
          f"| {f(r['dem_s_simulated'], '.4f')} | {f(r['fluid_s_amortized'], '.4f')} "
          f"| {f(100 * float(r['share_inter_physics']), '.3f')} "
          f"| {f(r.get('model_step_s_amortized', ''), '.4f')} "
          f"| {f(100 * float(err), '+.0f') + ' %' if err else '-'} "
          f"| {f(r['speedup'], '.0f')} / {f(r['speedup_fluid'], '.0f')} / {f(r['speedup_dem'], '.0f')} "
          f"| {f(float(r['simulation_wall_s']) / 60, '.1f')} min "
          f"| {f(float(r['simulation_peak_mib']) / 1024, '.1f')} GiB |")

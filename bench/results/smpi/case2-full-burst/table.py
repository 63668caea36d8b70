#!/usr/bin/python3
"""The docs' table of simulated points beside the model (docs/smpi.md, "The four strategies with
both corrections"): one row per STRATEGY-npP/report.json under DIR, the model's columns from the
smpi_scaling*.csv files in CSVDIR, speedups over the 1-rank real run CALIBRATION.

    table.py DIR CALIBRATION [CSVDIR]     e.g. table.py points-both ../case2-full/calibration-np1-report.json .

The simulation's wall time and memory come from the point's smpi.log (DIR/STRATEGY-npP/smpi.log,
or smpi_scaling.py's DIR/STRATEGY-npP.smpi.log)."""
import csv
import glob
import json
import os
import re
import sys

d, cal = sys.argv[1], sys.argv[2]
csvdir = sys.argv[3] if len(sys.argv) > 3 else d
r1 = json.load(open(cal))
st1 = r1["run"]["wall_s"] / r1["run"]["steps"]
model = {}
for f in glob.glob(os.path.join(csvdir, "smpi_scaling*.csv")):
    for r in csv.DictReader([l for l in open(f) if not l.startswith("#")]):
        model[(r["strategy"], int(r["ranks"]))] = r
order = {"uniform": 0, "balanced": 1, "tiled": 2, "independent": 3}
out = []
for f in glob.glob(os.path.join(d, "*-np*", "report.json")):
    point = os.path.dirname(f)
    s, p = os.path.basename(point).split("-np")
    p = int(p)
    r = json.load(open(f))
    t = r["timers"]
    st = r["run"]["wall_s"] / r["run"]["steps"]
    g = lambda k: t.get(k, {}).get("max", 0.0)
    a, b = g("fluid_pressure_assemble"), g("fluid_pressure_solve")
    logs = [l for l in (os.path.join(point, "smpi.log"), point + ".smpi.log") if os.path.exists(l)]
    m = re.search(r"wall ([0-9.]+) s, peak memory ([0-9.]+) MiB", open(logs[0]).read()) if logs else None
    fr = r["fractions"]
    mo = model.get((s, p))
    row = (f"| {s} | {p} | {st:.3f} | {a:.3f} / {b:.3f} | {st - a - b:.4f} | {g('fluid_halo'):.4f} | "
           f"{100 * fr['fv']:.0f} / {100 * fr['coupling']:.1f} / {100 * fr['inter_physics']:.2f} / "
           f"{100 * fr['wait']:.1f} | ")
    if mo and mo.get("model_step_s"):
        ms = float(mo["model_step_s"])
        row += f"{ms:.4f} | {100 * float(mo['model_error']):+.0f} % | {st1 / st:.1f} / {st1 / ms:.1f} | "
    else:
        row += "— | — | — | "
    row += f"{float(m.group(1)) / 60:.1f} min | {float(m.group(2)) / 1024:.1f} GiB |" if m else "— | — |"
    out.append((order[s], p, row))
print("| strategy | ranks | step (s) | pressure set-up / solve (s) | the rest (s) | fluid halo (s) | "
      "fluid / coupling / inter-physics / wait % | model step (s) | model error | speedup over 1 "
      "real rank, simulated / model | wall | memory |")
print("|---|---:|---:|---|---:|---:|---|---:|---:|---|---:|---:|")
for _, _, line in sorted(out):
    print(line)

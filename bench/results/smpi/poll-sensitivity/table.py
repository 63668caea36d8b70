#!/usr/bin/python3
"""The table of run.sh: simulated pressure set-up, solve and assembly (slowest rank, ms) and the
simulation's wall time for each rank count and simulated MPI_Iprobe cost.   table.py OUT"""
import glob
import json
import os
import re
import sys

out = sys.argv[1]
rows = []
for p in glob.glob(os.path.join(out, "np*", "report.json")):
    name = os.path.basename(os.path.dirname(p))
    m = re.match(r"np(\d+)-(measured|ip(.+))$", name)
    r = json.load(open(p))
    t = r["timers"]
    log = open(os.path.join(out, name + ".log")).read()
    wall = re.search(r"wall ([0-9.]+) s", log)
    ip = re.search(r"smpi/iprobe:([0-9.e+-]+)", log)
    probe = m.group(3) if m.group(3) else "measured"
    rows.append((int(m.group(1)), 0 if probe == "measured" else float(probe), probe,
                 t["fluid_pressure_setup"]["max"], t["fluid_pressure_solve"]["max"],
                 t["fluid_pressure_assemble"]["max"], float(wall.group(1)) if wall else 0.0))
print("| ranks | smpi/iprobe (s) | pressure set-up (ms) | solve (ms) | assembly (ms) | simulation wall (s) |")
print("|---:|---|---:|---:|---:|---:|")
for np, _, probe, su, so, asm, wall in sorted(rows):
    print(f"| {np} | {probe} | {1e3 * su:.1f} | {1e3 * so:.1f} | {1e3 * asm:.2f} | {wall:.1f} |")

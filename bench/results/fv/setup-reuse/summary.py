#!/usr/bin/python3
"""Medians over the rounds of ab.sh's CSVs (ms a step; CPU of the pressure phases, rank average):
   summary.py CSV...   -> a markdown table, one row a case, rank count and variant."""
import csv
import statistics
import sys

rows = {}
for path in sys.argv[1:]:
    for r in csv.DictReader(open(path)):
        rows.setdefault((r["case"], int(r["ranks"]), r["label"]), []).append(r)
print("| case | ranks | variant | step (ms) | assembly + set-up (ms) | solve (ms) | PCG iterations a step | set-ups a run |")
print("|---|---:|---|---:|---:|---:|---:|---:|")
med = lambda rs, k: statistics.median(float(r[k]) for r in rs)
for (case, np, label), rs in sorted(rows.items(), key=lambda kv: (kv[0][0], kv[0][1], int(kv[0][2][1:]) if kv[0][2][1:].isdigit() else 0)):
    print(f"| {case} | {np} | {label} | {1e3 * med(rs, 'step_s'):.2f} "
          f"| {1e3 * (med(rs, 'assemble_s') + med(rs, 'setup_s')):.2f} | {1e3 * med(rs, 'solve_s'):.2f} "
          f"| {med(rs, 'iterations'):.3f} | {rs[0]['setups']} of {rs[0]['steps']} |")

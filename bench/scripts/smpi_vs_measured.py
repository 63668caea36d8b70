#!/usr/bin/env python3
"""Simulated (SimGrid SMPI) vs measured vs modelled step time and shares, per case and rank count.

    bench/scripts/smpi_vs_measured.py --model DIR --smpi DIR [--out FILE.md]

--model: validate_model.py's output folder (validate-CASE.csv: the model and the measured
median at each rank count, the model calibrated on the 1-rank runs only). --smpi: a folder of
smpi_scaling.py outputs, one per case and rank count (CASE-npN/smpi_scaling.csv) or one per case
(CASE/smpi_scaling.csv), uniform strategy. Prints a Markdown table per case (and writes it to
--out): the step time measured, simulated and modelled with their errors against the
measurement, then the shares (fluid, DEM, coupling, inter-physics, wait) of each. Made by
bench/scripts/many_core_check.sh; the tolerance the docs hold SMPI to is 15 % of the step and
of each share (1.5 points where that is larger), as validate_model.py does for the model.
"""
import argparse
import csv
import glob
import os
import sys

SHARES = [("fluid", "fv"), ("dem", "dem"), ("coupling", "coupling"),
          ("inter_physics", "inter_physics"), ("wait", "wait")]
TOL, FLOOR = 0.15, 0.015


def read_validate(path):
    """{ranks: {quantity: (model, measured)}} of validate_model.py's CSV."""
    out = {}
    with open(path) as f:
        for row in csv.DictReader(ln for ln in f if not ln.startswith("#")):
            if row["quantity"] == "iterations" or not row["measured"]:
                continue
            model = float(row["model"]) if row["model"] else float("nan")
            out.setdefault(int(row["ranks"]), {})[row["quantity"]] = (model,
                                                                      float(row["measured"]))
    return out


def read_smpi(folder, case):
    """{ranks: row} of the simulated points of CASE (uniform strategy)."""
    rows = {}
    paths = glob.glob(os.path.join(folder, case + "-np*", "smpi_scaling.csv")) + \
        glob.glob(os.path.join(folder, case, "smpi_scaling.csv"))
    for p in paths:
        with open(p) as f:
            lines = [ln for ln in f if not ln.startswith("#")]
        for row in csv.DictReader(lines):
            if row["strategy"] == "uniform":
                rows[int(row["ranks"])] = row
    return rows


def table(case, val, sim):
    ok = True
    lines = [f"## {case}", "",
             "| ranks | measured s/step | SMPI s/step | SMPI error | model s/step | model error |",
             "|---|---|---|---|---|---|"]
    for P in sorted(val):
        model, meas = val[P]["step_s"]
        s = sim.get(P)
        s_step = float(s["step_s_simulated"]) if s else float("nan")
        e_s = (s_step - meas) / meas
        e_m = (model - meas) / meas
        ok &= (abs(e_s) <= TOL) if s else True
        lines.append(f"| {P} | {meas:.5f} | {s_step:.5f} | {100 * e_s:+.1f} % | {model:.5f} | "
                     f"{100 * e_m:+.1f} % |")
    lines += ["", "Shares of the step, % (measured / SMPI / model):", "",
              "| ranks | " + " | ".join(q for q, _ in SHARES) + " |",
              "|---|" + "---|" * len(SHARES)]
    for P in sorted(val):
        s = sim.get(P)
        cells = []
        for q, k in SHARES:
            model, meas = val[P].get(q, (float("nan"), float("nan")))
            sv = float(s["share_" + k]) if s else float("nan")
            cells.append(f"{100 * meas:.1f} / {100 * sv:.1f} / {100 * model:.1f}")
            if s and abs(sv - meas) > max(TOL * meas, FLOOR):
                ok = False
        lines.append(f"| {P} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append(f"SMPI within {100 * TOL:.0f} % of the measurement at every point: "
                 f"{'yes' if ok else 'no'}")
    lines.append("")
    return lines, ok


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True)
    ap.add_argument("--smpi", required=True)
    ap.add_argument("--out")
    a = ap.parse_args()
    lines = ["# SMPI vs measured vs model (uniform strategy; SMPI and the model without memory "
             "contention unless the model's stream profile says otherwise)", ""]
    found = False
    for path in sorted(glob.glob(os.path.join(a.model, "validate-*.csv"))):
        case = os.path.basename(path)[len("validate-"):-len(".csv")]
        t, _ = table(case, read_validate(path), read_smpi(a.smpi, case))
        lines += t
        found = True
    if not found:
        sys.exit(f"smpi_vs_measured.py: no validate-*.csv under {a.model}")
    text = "\n".join(lines)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Strong scaling of a case on a simulated cluster (SimGrid SMPI build; docs/smpi.md).

    bench/scripts/smpi_scaling.py bench/cases/case2-small.json --ranks 28,56 \
        --strategies uniform,tiled --platform paper --steps 2 [--set KEY=VALUE ...] [--out DIR]

Runs the SMPI build (bench/scripts/smpi_run.py) once per strategy and rank count and writes
DIR/smpi_scaling.csv and DIR/smpi_scaling.png (default DIR: ./out/<case>-smpi-scaling): the
SIMULATED time per step, speedup against the fewest ranks of the same strategy, the phase shares
(fluid, DEM, coupling, inter-physics, wait) from report.json, and what each simulation cost (wall
time, peak memory), and `burst_charge_us`, the charge of an empty burst smpi_run.py measured
and subtracted from every burst of that run. Every time in them is simulated and contention-free
(SMPI runs each rank's bursts alone on this machine's core); the figure says so in its title.

--model R.json: beside each simulated point, bench/scripts/model.py's prediction for the same
case, strategy, rank count and platform, with the same assumption (no memory contention, no
noise): R.json is a 1-rank report.json of the real build (calibrated here) or a costs file
(validate_model.py's validate-costs-CASE.json, `model.py calibrate`); the layouts come from
`coloc plan` of the real build (--coloc). The platform's links give the model's network: latency
two links (node, switch, node), bandwidth one link shared by the ranks of a node. The CSV gets
model_step_s, model_error (model / simulated - 1) and the model's shares; the figure draws the
model dashed. `dem_s_simulated` and `pressure_s_simulated` are the simulated DEM phases and
hypre's set-up and solve a step (rank averages); `model_dem_s` and `model_error_dem` compare the
model's DEM alone, since SMPI over-charges hypre's many small bursts (docs/smpi.md), less
so since the charge of an empty burst is subtracted. Calibrate on a 1-rank run of the points'
per-rank size (a simulated rank, like a real one at tens of ranks, works on a part that fits its
caches: case 3's DEM costs 5x more a particle-step in a 10 M-particle run on one rank than in
case3-small's 250 k) and give --model-iterations point when that run's PCG iterations are not the
case's. The paper's figures are drawn where it gives them (case 2 at 252 cores: 81 %
fluid, 18 % DummyDEM, < 1 % inter-physics; case 3: > 92 % DEM, < 8 % fluid, < 0.1 %
inter-physics; independent partitions after SediFoam: ~30 % inter-physics above 200 ranks).

--resume: a point whose run folder already holds a report.json of the same --steps and the
simulation's log (DIR/STRATEGY-npP.smpi.log, written after a run that ended well) is read instead
of simulated again, so a sweep that was stopped goes on where it stopped.

--plot-only CSV [--png PNG]: the figure again from a CSV this script wrote (bench/results/smpi/).
The figure is stamped with the simulated runs' provenance (bench/scripts/provenance.py; the CSV's
sidecar smpi_scaling.csv.provenance.json keeps it for --plot-only).
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys

import dense_bed
import model
import provenance
import smpi_run

HERE = os.path.dirname(os.path.abspath(__file__))
SHARES = ["fv", "dem", "coupling", "inter_physics", "wait"]
REPORTS = []  # the simulated runs' report.json (their provenance stamps the figure)


# The paper's figures (Pozzetti et al.), % of the step: (case name prefix, ranks, share, value, how)
PAPER = [("case2", 252, "fv", 81.0, "="), ("case2", 252, "dem", 18.0, "="),
         ("case2", 252, "inter_physics", 1.0, "<"), ("case3", 280, "dem", 92.0, ">"),
         ("case3", 280, "fv", 8.0, "<"), ("case3", 280, "inter_physics", 0.1, "<")]
SEDIFOAM_INDEPENDENT = 30.0  # % inter-physics, independent partitions above 200 ranks
UNITS = {"": 1.0, "k": 1e3, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}
TIME = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}


def platform_profile(path):
    """model.py's network profile from the platform's <cluster>: latency of two links, bandwidth
    of one link (bytes/s) shared by the ranks of a node, no memory contention, no noise."""
    at = smpi_run.cluster_attributes(path)
    bw = re.fullmatch(r"([0-9.eE+-]+)\s*([kKMGT]?)(Bps|bps)", at["bw"])
    lat = re.fullmatch(r"([0-9.eE+-]+)\s*(s|ms|us|ns)", at["lat"])
    if not bw or not lat:
        sys.exit(f"smpi_scaling.py: {path}: bw '{at['bw']}' or lat '{at['lat']}' not understood")
    bps = float(bw.group(1)) * UNITS[bw.group(2)] / (8.0 if bw.group(3) == "bps" else 1.0)
    return {"latency_s": 2 * float(lat.group(1)) * TIME[lat.group(2)], "bandwidth_Bps": bps,
            "ranks_per_node": int(at.get("core", "1")), "memory_Bps": bps, "memory": None,
            "noise": None, "name": os.path.basename(path) + " (contention-free)"}


def model_points(a, strategies, ranks, out, rows):
    """{(strategy, ranks): (model.py's prediction with the run's set-ups a step, with a long
    run's: 1 / setup_interval)} for the simulated points."""
    with open(a.model) as f:
        src = json.load(f)
    costs = model.calibrate(src, "avg") if "timers" in src else src
    prof = platform_profile(smpi_run.platform_file(a.platform))
    plan_dir = os.path.join(out, "plan")
    cmd = [a.coloc, "plan", a.case, "--ranks", ",".join(str(p) for p in ranks), "--out", plan_dir]
    for s in strategies:
        cmd += ["--strategy", s]
    for kv in case_sets(a):
        cmd += ["--set", kv]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"smpi_scaling.py: coloc plan failed:\n{p.stdout}{p.stderr}")
    with open(os.path.join(plan_dir, "plan.json")) as f:
        plan = json.load(f)
    runs = {(r["strategy"], r["ranks"]): r for r in rows}
    out_pts = {}
    for L in plan["layouts"]:
        r = runs.get((L["strategy"], L["ranks"]))
        if "error" in L or r is None:
            continue
        as_run = r["setups"] / a.steps
        long_run = 1.0 / max(1, r["setup_interval"])
        c = costs
        if a.model_iterations == "point" and r["pressure_iterations"] != "":
            # PCG's iterations a step are the case's (rank-independent to the solver's
            # tolerance), not the machine's: the point's own, the unit costs the calibration's
            c = {**costs, "pressure_iterations_per_step": float(r["pressure_iterations"])}
        out_pts[(L["strategy"], L["ranks"])] = (
            model.predict_layout(c, L, prof, setups_per_step=as_run),
            model.predict_layout(c, L, prof, setups_per_step=long_run))
    return out_pts, costs["source"], prof["name"]


def case_sets(a):
    sets = list(a.set)
    if a.dense_bed:
        sets.append(dense_bed.set_argument(a.case, a.dense_bed))
    return sets


def case_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def run_one(a, strategy, ranks, folder):
    cmd = [sys.executable, os.path.join(HERE, "smpi_run.py"), "--ranks", str(ranks), "--platform",
           a.platform]
    if a.smpi_build:
        cmd += ["--smpi-build", a.smpi_build]
    if a.burst_charge:
        cmd += ["--burst-charge", a.burst_charge]
    if a.real_build:
        cmd += ["--real-build", a.real_build]
    cmd += ["--", "run", a.case, "--quiet", "--overwrite", "--set", f"run.steps={a.steps}",
            "--set", f"partition.strategy={strategy}", "--out", folder]
    for kv in case_sets(a):
        cmd += ["--set", kv]
    log = folder + ".smpi.log"  # smpi_run.py's output: the simulation's wall time and memory
    rep_path = os.path.join(folder, "report.json")
    kept = a.resume and os.path.exists(log) and os.path.exists(rep_path)
    if kept:
        text, rc = open(log).read(), 0
        print(f"smpi_scaling.py: {strategy} at {ranks} ranks: kept from {log} (--resume)")
    else:
        out = subprocess.run(cmd, capture_output=True, text=True)
        sys.stdout.write(out.stdout)
        sys.stderr.write(out.stderr)
        text, rc = out.stdout, out.returncode
        if os.path.exists(log):
            os.remove(log)
    m = re.search(r"wall ([0-9.]+) s, peak memory ([0-9.]+) MiB, exit (\d+)", text)
    if rc != 0 or not m:
        sys.exit(f"smpi_scaling.py: {strategy} at {ranks} ranks failed (exit {rc})")
    rep = json.load(open(rep_path))
    if rep.get("run", {}).get("steps") != a.steps:
        sys.exit(f"smpi_scaling.py: {rep_path} ran {rep.get('run', {}).get('steps')} steps, "
                 f"not --steps {a.steps}: run without --resume")
    if not kept:
        with open(log, "w") as f:
            f.write(text)
    REPORTS.append(rep)
    if not rep.get("provenance", {}).get("simulated", False):
        sys.exit(f"smpi_scaling.py: {folder}/report.json is not from a simulated run")
    row = {"strategy": strategy, "ranks": ranks,
           "step_s_simulated": rep["run"]["wall_s"] / rep["run"]["steps"],
           "simulation_wall_s": float(m.group(1)), "simulation_peak_mib": float(m.group(2))}
    # what smpi_run.py subtracted from each burst (the charge of an empty burst; absent in logs
    # of simulations made before it did)
    b = re.search(r"burst charge subtracted ([0-9.]+) us", text)
    row["burst_charge_us"] = float(b.group(1)) if b else ""
    for k in SHARES:
        row["share_" + k] = rep["fractions"].get(k, 0.0)
    # grouped as the model groups them: its DEM share is the DEM work and the ghost updates
    steps = rep["run"]["steps"]
    tg = model.group_times(rep, "avg")
    row["dem_s_simulated"] = (tg["dem"] + model.timer(rep, "dem_ghost", "avg")) / steps
    row["pressure_s_simulated"] = (tg["pressure_setup"] + tg["pressure_solve"]) / steps
    # the fluid part of the coupled step (its phases, halos included) for its own speed-up
    row["fluid_s_simulated"] = (tg["fluid"] + tg["pressure_setup"] + tg["pressure_solve"] +
                                model.timer(rep, "fluid_halo", "avg")) / steps
    # hypre's set-ups (fluid.pressure.setup_interval): a run of a few steps holds one, a long run
    # one every `interval` steps. step_s_amortized is the simulated step with the set-ups of a
    # long run: the run's set-up time (slowest rank, fluid_pressure_setup) spread as 1/interval
    # instead of setups/steps; without that timer (older builds) it is the step as simulated.
    pres = rep.get("pressure", {})
    setups, interval = pres.get("setups", steps), pres.get("setup_interval", 1)
    row["setups"], row["setup_interval"] = setups, interval
    row["pressure_iterations"] = pres.get("iterations_avg", "")
    su = model.timer(rep, "fluid_pressure_setup", "max")
    each = su / setups if setups else 0.0
    row["pressure_setup_each_s"] = each
    amort = row["step_s_simulated"] - each * (setups / steps - 1.0 / max(1, interval))
    row["step_s_amortized"] = amort if "fluid_pressure_setup" in rep["timers"] else row["step_s_simulated"]
    row["fluid_s_amortized"] = row["fluid_s_simulated"] - (
        model.timer(rep, "fluid_pressure_setup", "avg") / steps) * (1 - steps / max(1, interval) / max(1, setups))
    cal = rep.get("provenance", {}).get("smpi_calibration", {})
    row["calibration_offset_us"] = 1e6 * cal["offset_s"] if "offset_s" in cal else ""
    row["particles"] = rep.get("bed", {}).get("particles", "")
    row["contacts_per_particle"] = rep.get("bed", {}).get("contacts_per_particle", "")
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", nargs="?")
    ap.add_argument("--ranks", help="comma-separated, e.g. 28,56,112 (required)")
    ap.add_argument("--strategies", default="uniform,balanced,tiled,independent")
    ap.add_argument("--platform", default="paper")
    ap.add_argument("--steps", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE for the case")
    ap.add_argument("--dense-bed", type=float, nargs="?", const=0.01, default=0.0,
                    metavar="OVERLAP", help="the bed starts dense and in contact (dense_bed.py; "
                    "neighbours overlap by OVERLAP of a diameter, default 0.01)")
    ap.add_argument("--smpi-build", help="the SMPI build folder (default: smpi_run.py's)")
    ap.add_argument("--burst-charge", help="passed to smpi_run.py: measured (its default), none "
                    "(SMPI's own charge of each burst) or seconds to subtract from each burst")
    ap.add_argument("--real-build", help="passed to smpi_run.py: the Open MPI build whose "
                    "bench_mpi_calls gives a real call's cost (default: smpi_run.py's, build/)")
    ap.add_argument("--resume", action="store_true", help="keep the points of an earlier run "
                    "of this command into the same --out (their report.json and .smpi.log): a "
                    "long sweep goes on where it stopped")
    ap.add_argument("--out", help="output folder (default: ./out/<case>-smpi-scaling)")
    ap.add_argument("--model", help="a 1-rank report.json of the real build, or a costs JSON: "
                    "model.py's prediction beside each point")
    ap.add_argument("--model-iterations", choices=("calibration", "point"), default="calibration",
                    help="the model's PCG iterations a step: the calibration run's (default) or "
                    "each simulated point's own (report pressure.iterations_avg), for a "
                    "calibration run of another size than the case (its unit costs at the "
                    "points' per-rank size)")
    ap.add_argument("--coloc", default=os.path.join(os.path.dirname(os.path.dirname(HERE)),
                                                    "build", "coloc"),
                    help="the real build's coloc, for `coloc plan` (--model)")
    ap.add_argument("--plot-only", metavar="CSV", help="re-draw the figure from a CSV this "
                    "script wrote (its first line gives platform, steps and the model's costs) "
                    "to --png (default: CSV with .png)")
    ap.add_argument("--png", help="with --plot-only: the figure's file")
    a = ap.parse_args()
    if a.plot_only:
        return plot_only(a.plot_only, a.png or os.path.splitext(a.plot_only)[0] + ".png")
    if not a.case or not a.ranks:
        ap.error("the case and --ranks are required (unless --plot-only)")
    ranks = [int(r) for r in a.ranks.split(",")]
    strategies = [s for s in a.strategies.split(",") if s]
    out = a.out or os.path.join("out", case_name(a.case) + "-smpi-scaling")
    os.makedirs(out, exist_ok=True)
    rows = []
    for s in strategies:
        for p in ranks:
            rows.append(run_one(a, s, p, os.path.join(out, f"{s}-np{p}")))
            first = next(r for r in rows if r["strategy"] == s)
            r = rows[-1]
            # speed-ups against the fewest ranks of the strategy, times that many: the coupled
            # step of a long run (set-ups amortised), and its fluid and DEM parts
            for key, col in (("speedup", "step_s_amortized"), ("speedup_as_run", "step_s_simulated"),
                             ("speedup_fluid", "fluid_s_amortized"), ("speedup_dem", "dem_s_simulated")):
                r[key] = (first[col] / r[col] * first["ranks"]) if r[col] > 0 else ""
    mod, mod_src, mod_prof = (model_points(a, strategies, ranks, out, rows) if a.model
                              else ({}, None, None))
    for r in rows:
        m = mod.get((r["strategy"], r["ranks"]))
        if m is None:
            continue
        m, ml = m
        first = next(x for x in rows if x["strategy"] == r["strategy"])
        m0 = mod[(first["strategy"], first["ranks"])][1]
        # the model with the run's own set-ups a step (as simulated), and with a long run's
        r["model_step_s"] = m["step_s"]
        r["model_error"] = m["step_s"] / r["step_s_simulated"] - 1.0
        r["model_step_s_amortized"] = ml["step_s"]
        r["model_error_amortized"] = ml["step_s"] / r["step_s_amortized"] - 1.0
        r["model_speedup"] = m0["step_s"] / ml["step_s"] * first["ranks"]
        m = ml
        # the DEM alone (rank average, ghosts included): the part of the step whose simulated
        # bursts are the code's own work; hypre's are over-charged by SMPI (docs/smpi.md)
        r["model_dem_s"] = m["step_s"] * m["dem"]
        if r["dem_s_simulated"] > 0:
            r["model_error_dem"] = r["model_dem_s"] / r["dem_s_simulated"] - 1.0
        for k, mk in (("fv", "fluid"), ("dem", "dem"), ("coupling", "coupling"),
                      ("inter_physics", "inter_physics"), ("wait", "wait")):
            r["model_share_" + k] = m[mk]
    path = os.path.join(out, "smpi_scaling.csv")
    with open(path, "w", newline="") as f:
        f.write(f"# SIMULATED (SimGrid SMPI, platform {a.platform}, contention-free): "
                f"{case_name(a.case)}, {a.steps} steps a run; speedup relative to the fewest "
                f"ranks of each strategy, times that many ranks"
                + (f"; MODEL columns: model.py, costs from {mod_src}, profile {mod_prof}"
                   if mod else "") + "\n")
        keys = [k for r in rows for k in r]
        w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(keys)), restval="")
        w.writeheader()
        w.writerows(rows)
    provenance.write_sidecar(path, REPORTS)  # smpi_scaling.csv.provenance.json
    print(f"smpi_scaling.py: wrote {path}")
    return plot(rows, strategies, ranks, case_name(a.case), a.platform, a.steps,
                mod_src if mod else None, os.path.join(out, "smpi_scaling.png"), REPORTS, [])


def plot_only(path, png):
    """The figure again from a CSV main() wrote: its first line names the platform, the steps
    and the model's costs."""
    with open(path) as f:
        head = f.readline()
        rows = []
        for r in csv.DictReader(f):
            row = {}
            for k, v in r.items():
                if v == "":
                    continue  # a column of other rows (the model's where it ran)
                try:
                    row[k] = float(v) if k != "strategy" else v
                except ValueError:
                    row[k] = v
            row["ranks"] = int(row["ranks"])
            rows.append(row)
    m = re.match(r"# SIMULATED \(SimGrid SMPI, platform (.*?), contention-free\): (.*?), (\d+) "
                 r"steps a run.*?(?:; MODEL columns: model.py, costs from (.*?), profile .*)?$",
                 head.strip())
    if not m:
        sys.exit(f"smpi_scaling.py: {path} does not start with this script's comment line")
    platform, name, steps, mod_src = m.group(1), m.group(2), int(m.group(3)), m.group(4)
    strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    ranks = sorted({r["ranks"] for r in rows})
    return plot(rows, strategies, ranks, name, platform, steps, mod_src, png, [], [path])


def plot(rows, strategies, ranks, name, platform, steps, mod_src, png, reports, data_files):
    """speedup, inter-physics share, fluid and DEM shares against the simulated ranks; the
    model's points dashed where the rows have them; stamped with the runs' provenance."""
    mod = mod_src is not None
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("smpi_scaling.py: no matplotlib, no figure")
        return 0
    fig, (ax1, ax0, ax2, ax3) = plt.subplots(1, 4, figsize=(20, 4.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    # as the paper draws it: the coupled step's speed-up beside its fluid and DEM parts', for
    # the co-located uniform partition (or the first strategy)
    ref = "uniform" if "uniform" in strategies else strategies[0]
    rr = [r for r in rows if r["strategy"] == ref]
    Pr = [r["ranks"] for r in rr]
    for key, style, label in (("speedup", "o-", "coupled"), ("speedup_fluid", "s--", "fluid part"),
                              ("speedup_dem", "^--", "DEM part")):
        pts = [(p, r[key]) for p, r in zip(Pr, rr) if r.get(key, "") != ""]
        if pts:
            ax0.plot([p for p, _ in pts], [v for _, v in pts], style, label=f"{ref}: {label}")
    ax0.plot([min(ranks), max(ranks)], [min(ranks), max(ranks)], "k:", label="ideal")
    ax0.set_title(f"{ref}: the coupled step and its parts", fontsize=9)
    for i, s in enumerate(strategies):
        c = colors[i % len(colors)]
        rs = [r for r in rows if r["strategy"] == s]
        P = [r["ranks"] for r in rs]
        ax1.plot(P, [r["speedup"] for r in rs], "o-", color=c, label=s + " (simulated)")
        ax2.plot(P, [100 * r["share_inter_physics"] for r in rs], "o-", color=c, label=s)
        ax3.plot(P, [100 * r["share_fv"] for r in rs], "o-", color=c, label=s + " fluid")
        ax3.plot(P, [100 * r["share_dem"] for r in rs], "s-", color=c, alpha=0.6,
                 label=s + " DEM")
        rm = [r for r in rs if "model_step_s" in r]
        if rm:
            Pm = [r["ranks"] for r in rm]
            ax1.plot(Pm, [r["model_speedup"] for r in rm], "x--", color=c, label=s + " (model)")
            ax2.plot(Pm, [100 * r["model_share_inter_physics"] for r in rm], "x--", color=c)
            ax3.plot(Pm, [100 * r["model_share_fv"] for r in rm], "x--", color=c)
            ax3.plot(Pm, [100 * r["model_share_dem"] for r in rm], "x:", color=c)
    lo, hi = min(ranks), max(ranks)
    ax1.plot([lo, hi], [lo, hi], "k:", label="ideal")
    marks = {"fv": ax3, "dem": ax3, "inter_physics": ax2}
    for prefix, P, share, v, how in PAPER:
        if name.startswith(prefix):
            marks[share].plot([P], [v], "k*", ms=10)
            marks[share].annotate(f"paper {share.replace('fv', 'fluid')} {how} {v:g} %", (P, v),
                                  fontsize=7, xytext=(4, 4), textcoords="offset points")
    if "independent" in strategies and hi >= 200:
        ax2.plot([200, max(hi, 280)], [SEDIFOAM_INDEPENDENT] * 2, "k--", lw=0.8,
                 label="independent after SediFoam (~30 %)")
    ax1.set_ylabel("speed-up (time a step, hypre set-ups of a long run)")
    ax0.set_ylabel("speed-up (time a step)")
    ax2.set_ylabel("inter-physics exchange, % of the step")
    ax3.set_ylabel("fluid (o) and DEM (s), % of the step")
    for ax in (ax1, ax0, ax2, ax3):
        ax.set_xlabel("simulated MPI ranks")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"SIMULATED (SimGrid SMPI, {platform} cluster, contention-free): {name}, "
                 f"{steps} steps; solid: simulated"
                 + (f", dashed: MODEL (model.py, same platform, costs from {mod_src})"
                    if mod else "") + "; *: the paper", fontsize=9)
    fig.tight_layout()
    provenance.stamp(fig, reports=reports, data_files=data_files)
    provenance.savefig(fig, png, dpi=110)
    print(f"smpi_scaling.py: wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

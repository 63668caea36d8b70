#!/usr/bin/python3
"""coloc against OpenFOAM (Debian `openfoam` v1912), one core each, back to back (issue 16).

    bench/peers/openfoam/openfoam_bench.py channel [--steps 20] [--rounds 3] [--dt 0.015]
    bench/peers/openfoam/openfoam_bench.py fbed [--settle-steps 230] [--coloc-steps 10]
        [--foam-steps 4] [--foam-dt S] [--rounds 3] [--particles N]

channel: bench/cases/fluid-channel.json against icoFoam (GAMG for the pressure). The script
writes the OpenFOAM case from the coloc case (blockMeshDict from `domain`, the boundary
conditions from `fluid.boundary`, nu, the pressure tolerance from `fluid.pressure.tol`) into
bench/peers/openfoam/channel/ (text, committed) and runs blockMesh once in --work. Each round runs
coloc for 1 step and for 1 + --steps steps (the difference is the cost of --steps warm steps, the
first step's multigrid set-up and the start-up excluded), then icoFoam for 1 + --steps steps
(its own ExecutionTime / ClockTime lines, the first step excluded), both under
`taskset -c --cpu`, with the same fixed dt. Pressure iterations a step: coloc's
pressure.iterations_avg, icoFoam's GAMG "No Iterations" summed over the PISO correctors.

fbed: bench/cases/fbed-100k.json against DPMFoam. coloc settles the layered bed (the script runs
bench/scripts/contact_bench.py --settle-only once: a checkpoint), the particle positions are read
from the checkpoint and given to DPMFoam as a manualInjection at t = 0 (so both start from the
same packed bed), then each round runs coloc restarted from the checkpoint for --coloc-steps
steps and DPMFoam for 1 + --foam-steps steps (the first, with the injection, excluded). The
measure is seconds per particle per DEM sub-step: the whole coupled step (fluid + particles +
coupling) divided by particles x sub-steps (coloc: particles.dt / fluid.dt sub-steps; DPMFoam:
the "move-collide subCycles" it prints, at least 1). Contacts per particle: coloc's
contacts_per_particle (series.csv), DPMFoam's from the positions it writes at the end (pairs
closer than the sum of the radii) and the same count on the injected positions.

Outputs: bench/results/openfoam/{channel,fbed}.csv (one row per run, with the load average) and
{channel,fbed}.md (medians, ratios per round). Work folders (meshes, logs, run outputs) under
--work (default out/openfoam/, not committed). Not part of CTest: OpenFOAM is not a dependency.
"""
import argparse
import csv
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

# the OpenFOAM case written from the coloc case, and the solver logs and particle positions
# read back: foam_case.py, beside this script
from foam_case import (HEADER, foam_positions, load_jsonc, per_step_foam, write_channel,
                       write_fbed)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
PY = "/usr/bin/python3"


_FOAM_ENV = None


def foam_env():
    """The environment after sourcing OpenFOAM's bashrc (its binaries need WM_PROJECT_DIR...)."""
    global _FOAM_ENV
    if _FOAM_ENV is None:
        rc = os.environ.get("FOAM_BASHRC", "/usr/share/openfoam/etc/bashrc")
        out = subprocess.run(["bash", "-c", f"source {rc} >/dev/null 2>&1; env -0"],
                             capture_output=True, check=True).stdout.decode()
        _FOAM_ENV = dict(kv.split("=", 1) for kv in out.split("\0") if "=" in kv)
    return _FOAM_ENV


def uptime():
    return open("/proc/loadavg").read().split()[0]


def now_utc():
    return time.strftime("%Y-%m-%d %H:%M", time.gmtime())


def earlier_rows(args, name, settings):
    """With --append: the rows already in the result CSV (numbers back as floats) and the next
    round's number, so that rounds run in separate invocations at different times end up in one
    table; the CSV's settings column must match this run's (no mixing of settings in a table).
    Without --append: no rows, round 0 (the CSV is rewritten)."""
    path = os.path.join(args.out, f"{name}.csv")
    if not args.append or not os.path.exists(path):
        return [], 0
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r.get("settings") != settings:
                sys.exit(f"openfoam_bench: {path} holds rows with settings "
                         f"'{r.get('settings')}', not '{settings}': use another --tag")
            row = {}
            for k, v in r.items():
                try:
                    row[k] = int(v) if k == "round" else (
                        v if k in ("code", "utc", "settings", "load1_before", "load1_after")
                        else float(v))
                except ValueError:
                    row[k] = v
            rows.append(row)
    return rows, 1 + max((r["round"] for r in rows), default=-1)


def timed(cmd, log, cwd=None, env=None):
    """Run cmd with stdout/stderr to log; return (wall s, child CPU s) of this run alone."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(log, "w") as f:
        rc = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=cwd, env=env).returncode
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if rc:
        sys.exit(f"openfoam_bench: {' '.join(cmd)} failed ({rc}); see {log}")
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


# ----------------------------------------------------------------------------------------------
# channel: icoFoam


def channel(args):
    cfg = load_jsonc(args.case)
    d = args.dict_dir
    work = os.path.join(args.work, "channel")
    write_channel(args.case, cfg, args.dt, args.steps + 1, args.n_correctors, d, args.p_reltol)
    if args.write_only:
        return
    foam = os.path.join(work, "foam")
    if args.remesh or not os.path.exists(os.path.join(foam, "constant/polyMesh/owner")):
        shutil.rmtree(foam, ignore_errors=True)
        shutil.copytree(d, foam, ignore=shutil.ignore_patterns("README*"))
        timed(["blockMesh"], os.path.join(work, "blockMesh.log"), cwd=foam, env=foam_env())
    else:  # keep the mesh, refresh the dictionaries
        for sub in ("system", "constant", "0"):
            for fn in os.listdir(os.path.join(d, sub)):
                shutil.copy(os.path.join(d, sub, fn), os.path.join(foam, sub, fn))
    ts = ["taskset", "-c", str(args.cpu)]
    sets = ["--set", "fluid.adaptive_dt=false", "--set", f"fluid.dt={args.dt}",
            "--set", "run.progress_interval_s=0", "--set", "output.snapshot=false"]
    for kv in args.coloc_set:
        sets += ["--set", kv]
    settings = (f"p_reltol={args.p_reltol:g} n_correctors={args.n_correctors} "
                f"steps={args.steps} dt={args.dt:g} cpu={args.cpu}"
                + "".join(f" coloc:{kv}" for kv in args.coloc_set))
    name = "channel" + args.tag
    rows, first = earlier_rows(args, name, settings)
    for rnd in range(first, first + args.rounds):
        for who in args.order.split(","):
            load, utc = uptime(), now_utc()
            if who == "coloc":
                res = {}
                for n in (1, args.steps + 1):
                    out = os.path.join(work, f"coloc-r{rnd}-n{n}")
                    wall, cpu = timed(ts + [args.coloc, "run", args.case, "--quiet", "--overwrite", "--out", out,
                                            "--set", f"run.steps={n}"] + sets,
                                      out + ".log")
                    rep = json.load(open(os.path.join(out, "report.json")))
                    res[n] = (wall, cpu, rep)
                (w1, c1, rep1), (wn, cn, rep) = res[1], res[args.steps + 1]
                its1 = rep1["pressure"]["iterations_avg"]  # the first step's
                row = {"code": "coloc", "round": rnd, "steps": args.steps,
                       "wall_s_per_step": (wn - w1) / args.steps,
                       "cpu_s_per_step": (cn - c1) / args.steps,
                       "p_iters_per_step": (rep["pressure"]["iterations_avg"] * (args.steps + 1)
                                            - its1) / args.steps,
                       "p_iters_first_step": its1,
                       "p_solves_per_step": 1}
            else:
                for t in os.listdir(foam):  # remove earlier time folders
                    if re.fullmatch(r"[0-9.e-]+", t) and t != "0":
                        shutil.rmtree(os.path.join(foam, t))
                log = os.path.join(work, f"icoFoam-r{rnd}.log")
                timed(ts + ["icoFoam"], log, cwd=foam, env=foam_env())
                cpu, wall, n, text = per_step_foam(log)
                its = [int(x) for x in re.findall(r"Solving for p,.*No Iterations (\d+)", text)]
                nc = args.n_correctors
                row = {"code": "icoFoam", "round": rnd, "steps": n, "wall_s_per_step": wall,
                       "cpu_s_per_step": cpu, "p_iters_per_step": sum(its[nc:]) / n,
                       "p_iters_first_step": sum(its[:nc]),
                       "p_solves_per_step": nc}
            row["load1_before"] = load
            row["load1_after"] = uptime()
            row["utc"] = utc
            row["settings"] = settings
            print("openfoam_bench:", row, flush=True)
            rows.append(row)
    write_table(args, name, rows, "icoFoam", "coloc", "s per step",
                "wall_s_per_step",
                "cpu_s_per_step", extra=channel_notes(args, cfg))


def reltol_words(args):
    if args.p_reltol > 0:
        return (f"p relTol {args.p_reltol:g} on the first corrector(s) and pFinal relTol 0 on "
                f"the last, as icoFoam's users run it")
    return "relTol 0 on every corrector"


def channel_notes(args, cfg):
    c = cfg["domain"]["cells"]
    return (f"Grid {c[0]} x {c[1]} x {c[2]} = {c[0] * c[1] * c[2]:,} cells, fixed dt {args.dt} s "
            f"for both, {args.steps} timed steps after a first one; pressure tolerance "
            f"{cfg['fluid']['pressure']['tol']:g} (coloc: L2 residual of the flux scale; "
            f"OpenFOAM: normalised L1 residual, {reltol_words(args)}); icoFoam PISO with "
            f"{args.n_correctors} corrector(s), GAMG (GaussSeidel), Euler, vanLeerV; coloc "
            + (f"as in the case file (PCG + PFMG weighted Jacobi, AB2, TVD van Leer)"
               if not args.coloc_set else
               f"as in the case file with {', '.join(args.coloc_set)} (PCG + PFMG, AB2, TVD van "
               f"Leer)") + ". "
            f"Both `taskset -c {args.cpu}`.")


def spread(v):
    """min / median / max of a list, as text."""
    return f"{min(v):.4g} / {statistics.median(v):.4g} / {max(v):.4g}"


def write_table(args, name, rows, peer, ours, unit, wkey, ckey, extra="", more=()):
    """The CSV (every row) and the markdown: per round both codes' wall and CPU figures, the
    ratios peer / ours, the pressure iterations (channel), the load before each run and the
    round's start (UTC); then min / median / max over the rounds of each ratio and of each
    code's figure, so that a reader sees which code moved."""
    os.makedirs(args.out, exist_ok=True)
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(os.path.join(args.out, f"{name}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    rounds = sorted({r["round"] for r in rows})
    by = {(r["code"], r["round"]): r for r in rows}
    chan = name.startswith("channel")
    head = (f"| round | start (UTC) | {peer} wall | {ours} wall | wall ratio | {peer} CPU | "
            f"{ours} CPU | CPU ratio |")
    if chan:
        head += f" {peer} p its/step | {ours} p its/step |"
    head += f" load 1 min ({peer}/{ours}) |"
    lines = [f"# coloc against OpenFOAM: {name}", "", extra, "",
             f"Figures in {unit}; ratio = {peer} / {ours} (above 1: coloc faster).", "", head,
             "|" + "---|" * head.count(" |")]
    rw, rc, pw, ow, pc, oc = [], [], [], [], [], []
    for k in rounds:
        p, o = by.get((peer, k)), by.get((ours, k))
        if not p or not o:
            continue
        pw.append(p[wkey]), ow.append(o[wkey]), pc.append(p[ckey]), oc.append(o[ckey])
        rw.append(p[wkey] / o[wkey])
        rc.append(p[ckey] / o[ckey])
        cells = [str(k), str(p.get("utc", "-")), f"{p[wkey]:.4g}", f"{o[wkey]:.4g}",
                 f"{rw[-1]:.2f}x", f"{p[ckey]:.4g}", f"{o[ckey]:.4g}", f"{rc[-1]:.2f}x"]
        if chan:
            cells += [f"{p['p_iters_per_step']:.2f}", f"{o['p_iters_per_step']:.2f}"]
        cells.append(f"{p['load1_before']}/{o['load1_before']}")
        lines.append("| " + " | ".join(cells) + " |")
    if rw:
        lines += ["", f"Over {len(rw)} rounds, min / median / max:", "",
                  "| | wall | CPU |", "|---|---|---|",
                  f"| ratio {peer} / {ours} | {spread(rw)} | {spread(rc)} |",
                  f"| {peer} ({unit}) | {spread(pw)} | {spread(pc)} |",
                  f"| {ours} ({unit}) | {spread(ow)} | {spread(oc)} |"]
    lines += list(more)
    with open(os.path.join(args.out, f"{name}.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


# ----------------------------------------------------------------------------------------------
# fbed: DPMFoam


def settled_positions(h5):
    import h5py
    import numpy as np
    with h5py.File(h5, "r") as f:
        found = {}

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                found[name] = obj
        f.visititems(visit)
        keys = sorted(found)
        pos = [k for k in keys if re.search(r"(^|/)(pos|position|positions|x)$", k)]
        rad = [k for k in keys if re.search(r"(^|/)(radius|r|radii)$", k)]
        if not pos:
            sys.exit(f"openfoam_bench: no positions in {h5}: {keys}")
        p = np.asarray(found[pos[0]][...], dtype=float).reshape(-1, 3)
        r = np.asarray(found[rad[0]][...], dtype=float).ravel() if rad else None
    return p, r


def contacts_per_particle(p, radius):
    from scipy.spatial import cKDTree
    pairs = cKDTree(p).query_pairs(2 * radius, output_type="ndarray")
    return 2.0 * len(pairs) / len(p) if len(p) else float("nan")


def fbed(args):
    import numpy as np
    cfg = load_jsonc(args.case)
    name = cfg["name"]
    work = os.path.join(args.work, "fbed")
    if args.write_only:  # the dictionaries alone (the radius of the case's first source)
        write_fbed(args.case, cfg, args.dict_dir, args.foam_dt or cfg["fluid"]["dt"],
                   args.foam_steps + 2, cfg["particles"]["sources"][0]["radius"], args.alpha,
                   args.collision_steps, args.drag, args.n_correctors, args.p_reltol)
        return
    os.makedirs(work, exist_ok=True)
    ckdir = os.path.join(work, "contact")
    ck = os.path.join(ckdir, "settled.h5")
    if not os.path.exists(ck):
        subprocess.run([PY, os.path.join(ROOT, "bench/scripts/contact_bench.py"), args.case,
                        "--settle-steps", str(args.settle_steps), "--settle-only",
                        "--coloc", args.coloc, "--work", ckdir,
                        "--launcher", f"taskset -c {args.cpu}",
                        "--out", os.path.join(work, "contact-out")], check=True)
    p, r = settled_positions(ck)
    radius = float(r[0]) if r is not None else cfg["particles"]["sources"][0]["radius"]
    n_all = len(p)
    if args.particles and args.particles < n_all:
        p = p[np.argsort(p[:, 2], kind="stable")[:args.particles]]  # the lowest: a packed bed
    cn0 = contacts_per_particle(p, radius)
    fl_dt, pa_dt = cfg["fluid"]["dt"], cfg["particles"]["dt"]
    sub = round(fl_dt / pa_dt)
    d = args.dict_dir
    # DPMFoam's time step: coloc's fluid step by default (DPMFoam then sub-cycles its collisions
    # by its own estimate from the fastest particle, 16 sub-cycles of 2.5e-5 s here); one step
    # more at each end: the first injects, the last writes the positions
    foam_dt = args.foam_dt or fl_dt
    steps = args.foam_steps + 2
    write_fbed(args.case, cfg, d, foam_dt, steps, radius, args.alpha, args.collision_steps,
               args.drag, args.n_correctors, args.p_reltol)
    foam = os.path.join(work, "foam")
    if args.remesh or not os.path.exists(os.path.join(foam, "constant/polyMesh/owner")):
        shutil.rmtree(foam, ignore_errors=True)
        shutil.copytree(d, foam, ignore=shutil.ignore_patterns("README*"))
        timed(["blockMesh"], os.path.join(work, "blockMesh.log"), cwd=foam, env=foam_env())
    for sub_d in ("system", "constant", "0"):
        for fn in os.listdir(os.path.join(d, sub_d)):
            shutil.copy(os.path.join(d, sub_d, fn), os.path.join(foam, sub_d, fn))
    with open(os.path.join(foam, "constant", "kinematicCloudPositions"), "w") as f:
        f.write(HEADER.format(case=os.path.relpath(ck, ROOT), cls="vectorField", loc="constant",
                              obj="kinematicCloudPositions"))
        f.write(f"{len(p)}\n(\n")
        f.writelines(f"({x:.9g} {y:.9g} {z:.9g})\n" for x, y, z in p)
        f.write(")\n")
    ts = ["taskset", "-c", str(args.cpu)]
    total = args.settle_steps + args.coloc_steps
    sets = ["--set", f"run.steps={total}", "--set", "run.progress_interval_s=0",
            "--set", f"output.diagnostics_interval={max(1, args.coloc_steps // 5)}"]
    if args.particles and args.particles < n_all:
        sys.exit("openfoam_bench: --particles below the case's count: coloc would need a case "
                 "with that many particles (not written by this script)")
    settings = (f"p_reltol={args.p_reltol:g} n_correctors={args.n_correctors} "
                f"foam_dt={foam_dt:g} foam_steps={args.foam_steps} coloc_steps={args.coloc_steps} "
                f"drag={args.drag} alpha={args.alpha:g} collision_steps={args.collision_steps} "
                f"cpu={args.cpu}")
    name = "fbed" + args.tag
    rows, first = earlier_rows(args, name, settings)
    for rnd in range(first, first + args.rounds):
        for who in args.order.split(","):
            load, utc = uptime(), now_utc()
            if who == "coloc":
                out = os.path.join(work, f"coloc-r{rnd}")
                wall, cpu = timed(ts + [args.coloc, "run", args.case, "--quiet", "--out", out,
                                        "--restart", ck] + sets, out + ".log")
                rep = json.load(open(os.path.join(out, "report.json")))
                steps = rep["run"]["steps"] - rep["run"].get("first_step", 0)
                # thread-CPU time of the step's phases (not the set-up with the checkpoint read,
                # not the diagnostics booked to output)
                busy = sum(v.get("busy_avg", 0.0) for k, v in rep["timers"].items()
                           if isinstance(v, dict) and k not in ("setup", "output"))
                cns = []
                with open(os.path.join(out, "series.csv")) as f:
                    for row_ in csv.DictReader(f):
                        if row_.get("contacts_per_particle"):
                            cns.append(float(row_["contacts_per_particle"]))
                n = rep["particles"]["count"]
                row = {"code": "coloc", "round": rnd, "steps": steps, "particles": n,
                       "substeps": sub,
                       "wall_s_per_step": rep["run"]["wall_s"] / steps,
                       "wall_ns_per_particle_substep": rep["run"]["wall_s"] / (steps * n * sub)
                       * 1e9,
                       "cpu_ns_per_particle_substep": busy / (steps * n * sub) * 1e9,
                       "contacts_per_particle": statistics.mean(cns) if cns else float("nan"),
                       "process_wall_s": wall, "process_cpu_s": cpu}
            else:
                for t in os.listdir(foam):
                    if re.fullmatch(r"[0-9.e-]+", t) and t != "0":
                        shutil.rmtree(os.path.join(foam, t))
                log = os.path.join(work, f"DPMFoam-r{rnd}.log")
                wall, cpu_all = timed(ts + ["DPMFoam"], log, cwd=foam, env=foam_env())
                cpu, wallps, nst, text = per_step_foam(log, skip=1, tail=1)
                # the log of each step ends at its ExecutionTime line; DPMFoam prints
                # "N move-collide subCycles" only when N > 1
                blocks = re.split(r"ExecutionTime = [^\n]*\n", text)[:-1]
                cyc = [int(m.group(1)) if m else 1 for m in
                       (re.search(r"(\d+) move-collide subCycles", b) for b in blocks)]
                # one "Current number of parcels" line per cloud evolution
                npar = [int(x) for x in re.findall(r"Current number of parcels\s*=\s*(\d+)", text)]
                subs = cyc[1:1 + nst]  # the timed steps: the 2nd to the last but one
                n = npar[-1] if npar else len(p)
                sub_mean = statistics.mean(subs)
                times = sorted((t for t in os.listdir(foam) if re.fullmatch(r"[0-9.e-]+", t)
                                and t != "0"), key=float)
                try:
                    cn = contacts_per_particle(foam_positions(foam, times[-1]), radius)
                except (OSError, IndexError):
                    cn = float("nan")
                row = {"code": "DPMFoam", "round": rnd, "steps": nst, "particles": n,
                       "substeps": sub_mean, "wall_s_per_step": wallps,
                       "wall_ns_per_particle_substep": wallps / (n * sub_mean) * 1e9,
                       "cpu_ns_per_particle_substep": cpu / (n * sub_mean) * 1e9,
                       "contacts_per_particle": cn,
                       "process_wall_s": wall, "process_cpu_s": cpu_all}
            row["load1_before"] = load
            row["load1_after"] = uptime()
            row["utc"] = utc
            row["settings"] = settings
            print("openfoam_bench:", row, flush=True)
            rows.append(row)
    notes = (f"{name}: {cfg['domain']['cells']} cells, {n_all:,} particles from coloc's settled "
             f"bed ({args.settle_steps} steps; coordination of the injected positions "
             f"{cn0:.2f}), fluid dt {fl_dt:g} s, coloc {sub} DEM sub-steps a fluid step; "
             f"DPMFoam deltaT {foam_dt:g} s, its own collision sub-cycles; "
             f"DPMFoam {args.drag}, pairSpringSliderDashpot (alpha {args.alpha:g}, b 1.5, "
             f"collisionResolutionSteps {args.collision_steps}), PIMPLE with "
             f"{args.n_correctors} corrector(s), "
             f"{'p relTol %g / pFinal relTol 0 (the Goldschmidt tutorial)' % args.p_reltol if args.p_reltol > 0 else 'relTol 0 on every corrector'}, "
             f"{args.foam_steps} timed steps "
             f"after the injection step; coloc {args.coloc_steps} steps restarted from the "
             f"checkpoint. Per particle-substep: the whole coupled step / (particles x "
             f"sub-steps). Both `taskset -c {args.cpu}`.")
    by = {(r["code"], r["round"]): r for r in rows}
    more = ["", "| round | DPMFoam sub-steps | DPMFoam contacts/particle | coloc contacts/particle "
                f"| DPMFoam s/step (of {foam_dt:g} s) | coloc s/step (of {fl_dt:g} s) |",
            "|---|---|---|---|---|---|"]
    for k in sorted({r["round"] for r in rows}):
        a, b = by.get(("DPMFoam", k)), by.get(("coloc", k))
        if a and b:
            more.append(f"| {k} | {a['substeps']:.3g} | {a['contacts_per_particle']:.2f} | "
                        f"{b['contacts_per_particle']:.2f} | {a['wall_s_per_step']:.4g} | "
                        f"{b['wall_s_per_step']:.4g} |")
    write_table(args, name, rows, "DPMFoam", "coloc", "ns per particle-substep",
                "wall_ns_per_particle_substep", "cpu_ns_per_particle_substep", extra=notes,
                more=more)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sp = ap.add_subparsers(dest="what", required=True)
    for what in ("channel", "fbed"):
        s = sp.add_parser(what)
        s.add_argument("--coloc", default=os.path.join(ROOT, "build", "coloc"))
        s.add_argument("--cpu", type=int, default=1, help="the core for taskset -c")
        s.add_argument("--rounds", type=int, default=3)
        s.add_argument("--work", default=os.path.join(ROOT, "out", "openfoam"))
        s.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "openfoam"))
        s.add_argument("--remesh", action="store_true")
        s.add_argument("--tag", default="", help="appended to the result file names")
        s.add_argument("--dict-dir", default=os.path.join(HERE, what),
                       help="where the OpenFOAM dictionaries are written (default: the "
                            "committed bench/peers/openfoam/<case>/)")
        s.add_argument("--write-only", action="store_true",
                       help="write the dictionaries into --dict-dir and stop (no run)")
        s.add_argument("--append", action="store_true",
                       help="add this invocation's rounds to the result CSV (same settings "
                            "only) and rewrite the markdown from all of them: rounds spread "
                            "over a session by running the script several times")
    c = sp.choices["channel"]
    c.add_argument("--case", default=os.path.join(ROOT, "bench/cases/fluid-channel.json"))
    c.add_argument("--steps", type=int, default=20, help="timed steps after a first one")
    c.add_argument("--dt", type=float, default=0.015)
    c.add_argument("--n-correctors", type=int, default=2, help="icoFoam PISO correctors")
    c.add_argument("--p-reltol", type=float, default=0.05,
                   help="GAMG relTol of p on the PISO correctors before the last (pFinal: "
                        "relTol 0 always); 0.05 as icoFoam's users run it, 0 the setting of "
                        "the first comparison (every corrector to the tolerance)")
    c.add_argument("--order", default="icoFoam,coloc")
    c.add_argument("--coloc-set", action="append", default=[], metavar="KEY=VALUE",
                   help="one more --set for coloc (repeatable; part of the settings), e.g. "
                        "fluid.pressure.pfmg.relax=rbgs")
    f = sp.choices["fbed"]
    f.add_argument("--case", default=os.path.join(ROOT, "bench/cases/fbed-100k.json"))
    f.add_argument("--settle-steps", type=int, default=230)
    f.add_argument("--coloc-steps", type=int, default=10)
    f.add_argument("--foam-steps", type=int, default=4, help="timed DPMFoam steps after the first")
    f.add_argument("--foam-dt", type=float, default=0.0,
                   help="DPMFoam's deltaT (default: the case's fluid.dt)")
    f.add_argument("--particles", type=int, default=0)
    f.add_argument("--alpha", type=float, default=0.075)
    f.add_argument("--collision-steps", type=int, default=12)
    f.add_argument("--drag", default="WenYuDrag")
    f.add_argument("--order", default="DPMFoam,coloc")
    f.add_argument("--n-correctors", type=int, default=2,
                   help="DPMFoam PIMPLE (PISO) correctors: 2 as in its Goldschmidt tutorial")
    f.add_argument("--p-reltol", type=float, default=0.01,
                   help="GAMG relTol of p before the last corrector (pFinal: 0); 0.01 as in the "
                        "Goldschmidt tutorial; --p-reltol 0 --n-correctors 1 is the setting of "
                        "the first comparison")
    args = ap.parse_args()
    args.case = os.path.abspath(args.case)
    args.coloc = os.path.abspath(args.coloc)
    {"channel": channel, "fbed": fbed}[args.what](args)


if __name__ == "__main__":
    main()

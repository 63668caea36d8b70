#!/usr/bin/python3
"""Minimum spouting velocity of bench/cases/spouted-bed.json, measured the standard way: the jet
velocity is decreased step by step from a stable spout until the spout collapses (U_ms is the
velocity at which spouting stops on decreasing flow), and compared with Mathur-Gishler.

    bench/scripts/spout_onset.py              # 1 rank, -> ./out/spout-onset/ (~2 min on the 2-core VM)
    bench/scripts/spout_onset.py --ranks 2 --velocities 25 20 15 12.5 10 --level-steps 2000
    bench/scripts/spout_onset.py --reuse --min-fountain 1   # the same runs, another threshold

How: a first run of the case with the jet at the highest velocity (--spinup-steps steps from the
case's initial bed) forms the spout and writes a checkpoint at its end; every following level
restarts from the previous level's checkpoint (--restart; the case file supplies the parameters,
so only the inlet patch's velocity changes, docs/output.md "Checkpoints and restart") and runs
--level-steps more steps at the next lower velocity. The particles are written every --every
steps (output.particles, no fields).

Criterion (the fountain): in each particle output, the annulus surface H_s is the 95th percentile
of the centre heights of the particles in the outer half of the bed (|x - x_jet| > W/4, W the
box's width along x; the script assumes gravity along -z, the jet an inlet patch on zlo and the
bed spread along x, as in the case); the fountain is the particles of the central half
(|x - x_jet| < W/4) whose centres are more than --above (default 4 diameters) above H_s. A level
spouts when the fountain holds at least --min-fountain particles (default 10) in every output of
the level's second half (the first half is left to the bed to adjust): a steady fountain, not one
that comes and goes (the table gives the mean too, so an intermittent spout shows as a mean well
above zero with a minimum of 0). The sweep stops after the first level that does not spout unless
--all.

U_ms is reported as the interval between the lowest level that spouts and the first that does not,
as the jet velocity and as the superficial velocity over the column (jet x slot area / column
cross-section), beside the Mathur-Gishler correlation
    U_ms = (d_p / D_c) (D_i / D_c)^(1/3) sqrt(2 g H (rho_p - rho_f) / rho_f)
for a cylindrical column, applied to the rectangular column and slot through equivalent
diameters (docs/benchmarks.md, "Spouted bed"): D = sqrt(4 A / pi) (same area) and D = 4 A / P
(hydraulic). H is the settled bed height (--bed-height; the default 0.05 m was measured for the
case's 8000 spheres: bed_height 4.8 cm, the highest centre 5.3 cm after 0.2 s without gas).

Run folders go under --out (default ./out/spout-onset; never bench/results unless given);
the table is printed and written to --out/spout_onset.md.
"""
import argparse
import glob
import json
import math
import os
import re
import shlex
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpi_env import mpi_env  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def env():
    return mpi_env()


def read_case(path):
    """The case file: JSON with // comment lines (the project's reader allows them)."""
    with open(path) as f:
        text = "\n".join(line for line in f if not line.lstrip().startswith("//"))
    return json.loads(text)


def jet_patch(case):
    for p in case.get("fluid", {}).get("patches", []):
        if p.get("type") == "inlet" and p.get("face") == "zlo":
            return p
    sys.exit("spout_onset.py: the case has no inlet patch on zlo (fluid.patches)")


def geometry(case):
    """Column cross-section, slot rectangle and the jet's x position (gravity along -z)."""
    lx, ly = case["domain"]["length"][0], case["domain"]["length"][1]
    ox = case["domain"].get("origin", [0.0, 0.0, 0.0])[0]
    p = jet_patch(case)
    sx, sy = p["max"][0] - p["min"][0], p["max"][1] - p["min"][1]
    return {"lx": lx, "ly": ly, "sx": sx, "sy": sy, "xjet": 0.5 * (p["min"][0] + p["max"][0]) - ox,
            "ox": ox}


def mathur_gishler(d_p, d_c, d_i, h, rho_p, rho_f, g=9.81):
    return (d_p / d_c) * (d_i / d_c) ** (1.0 / 3.0) * math.sqrt(2 * g * h * (rho_p - rho_f) / rho_f)


def correlations(case, geo, h):
    mat = case["particles"]["materials"][0]
    rho_p, rho_f = mat["density"], case["fluid"]["rho"]
    d_p = 2 * case["particles"]["sources"][0]["radius"]
    a_c, a_i = geo["lx"] * geo["ly"], geo["sx"] * geo["sy"]
    out = []
    for name, dc, di in (
            ("equal area, D = sqrt(4A/pi)", math.sqrt(4 * a_c / math.pi), math.sqrt(4 * a_i / math.pi)),
            ("hydraulic, D = 4A/P", 4 * a_c / (2 * (geo["lx"] + geo["ly"])),
             4 * a_i / (2 * (geo["sx"] + geo["sy"])))):
        u = mathur_gishler(d_p, dc, di, h, rho_p, rho_f)
        out.append((name, dc, di, u, u * a_c / a_i))
    return out


def fountain(path, geo, d_p, above):
    """(fountain count, annulus surface H_s, highest centre, mean vz of the central half in the bed)"""
    import h5py
    import numpy as np
    with h5py.File(path, "r") as f:
        x, v = f["x"][...], f["v"][...]
    dx = np.abs(x[:, 0] - geo["ox"] - geo["xjet"])
    outer, inner = dx > geo["lx"] / 4, dx <= geo["lx"] / 4
    hs = float(np.percentile(x[outer, 2], 95)) if outer.any() else 0.0
    f_count = int(np.sum(inner & (x[:, 2] > hs + above * d_p)))
    spout = inner & (x[:, 2] < hs)
    vz = float(v[spout, 2].mean()) if spout.any() else 0.0
    return f_count, hs, float(x[:, 2].max()), vz


def level_outputs(folder, first_step):
    files = []
    for p in glob.glob(os.path.join(folder, "particles_*.h5")):
        step = int(re.search(r"particles_(\d+)\.h5$", p).group(1))
        if step > first_step:
            files.append((step, p))
    return sorted(files)


def velocity_set(patch, u):
    q = dict(patch)
    q["velocity"] = [0.0, 0.0, float(u)]
    return "fluid.patches=" + json.dumps([q], separators=(",", ":"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    ap.add_argument("--case", default=os.path.join(ROOT, "bench/cases/spouted-bed.json"))
    ap.add_argument("--coloc", default=os.path.join(ROOT, "build/coloc"))
    ap.add_argument("--ranks", type=int, default=1, help="MPI ranks of each run (default 1)")
    ap.add_argument("--launcher", default="mpirun -n {n}",
                    help="command before coloc; {n} is --ranks (default 'mpirun -n {n}')")
    ap.add_argument("--velocities", type=float, nargs="+",
                    default=[20.0, 17.5, 15.0, 13.75, 12.5, 11.25, 10.0],
                    help="jet (slot) superficial velocities in m/s, decreasing; the first one forms "
                         "the spout (default 20 17.5 15 13.75 12.5 11.25 10; 20 is the case's)")
    ap.add_argument("--spinup-steps", type=int, default=3000,
                    help="steps of the first level, from the case's initial bed (default 3000)")
    ap.add_argument("--level-steps", type=int, default=2000,
                    help="steps of every further level (default 2000)")
    ap.add_argument("--every", type=int, default=200, help="particle output interval (steps)")
    ap.add_argument("--above", type=float, default=4.0,
                    help="fountain: centres this many particle diameters above H_s (default 4)")
    ap.add_argument("--min-fountain", type=float, default=10.0,
                    help="a level spouts when every output of its second half has at least this "
                         "many fountain particles (default 10)")
    ap.add_argument("--bed-height", type=float, default=0.05,
                    help="settled bed height H for Mathur-Gishler, m (default 0.05)")
    ap.add_argument("--all", action="store_true", help="run every level, also after a collapse")
    ap.add_argument("--reuse", action="store_true",
                    help="do not rerun a level whose folder already holds its report.json and "
                         "checkpoint (evaluate again, e.g. with another --min-fountain)")
    ap.add_argument("--out", default=os.path.join(os.getcwd(), "out", "spout-onset"),
                    help="folder for the runs and spout_onset.md (default ./out/spout-onset)")
    ap.add_argument("--set", action="append", default=[], help="extra --set for every run")
    args = ap.parse_args()

    vels = args.velocities
    if any(b >= a for a, b in zip(vels, vels[1:])):
        sys.exit("spout_onset.py: --velocities must decrease")
    case = read_case(args.case)
    geo = geometry(case)
    patch = jet_patch(case)
    d_p = 2 * case["particles"]["sources"][0]["radius"]
    area_ratio = (geo["sx"] * geo["sy"]) / (geo["lx"] * geo["ly"])
    os.makedirs(args.out, exist_ok=True)

    rows, prev, steps = [], None, 0
    for k, u in enumerate(vels):
        first = steps
        steps += args.spinup_steps if k == 0 else args.level_steps
        folder = os.path.join(args.out, "u%05.2f" % u)
        cmd = shlex.split(args.launcher.format(n=args.ranks)) + [
            args.coloc, "run", args.case, "--quiet", "--overwrite", "--out", folder,
            "--set", velocity_set(patch, u), "--set", "run.steps=%d" % steps,
            "--set", "output.interval_steps=%d" % args.every, "--set", "output.fields=false",
            "--set", "output.snapshot=false", "--set", "output.checkpoint_interval=%d" % steps]
        if prev:
            cmd += ["--restart", os.path.join(prev, "checkpoint.h5")]
        for s in args.set:
            cmd += ["--set", s]
        print("spout_onset: jet %.2f m/s, steps %d..%d: %s" % (u, first, steps, " ".join(
            shlex.quote(c) for c in cmd)), flush=True)
        report = os.path.join(folder, "report.json")
        done = False
        if args.reuse and os.path.exists(report) and os.path.exists(
                os.path.join(folder, "checkpoint.h5")):
            with open(report) as f:
                rep = json.load(f)
            done = rep.get("status") == "ok" and rep["run"]["steps"] == steps
        t0 = time.time()
        if done:
            print("spout_onset:   reused (--reuse)", flush=True)
            wall = rep["run"]["wall_s"]
        else:
            subprocess.run(cmd, check=True, env=env(), stdout=subprocess.DEVNULL)
            wall = time.time() - t0
        outs = level_outputs(folder, first)
        late = [p for s, p in outs if s > first + (steps - first) / 2]
        if not late:
            sys.exit("spout_onset.py: %s has no particle output in the level's second half "
                     "(--every %d, %d steps)" % (folder, args.every, steps - first))
        vals = [fountain(p, geo, d_p, args.above) for p in late]
        mean_f = sum(v[0] for v in vals) / len(vals)
        row = {"u_jet": u, "u_column": u * area_ratio, "fountain": mean_f,
               "fountain_min": min(v[0] for v in vals), "h_s": sum(v[1] for v in vals) / len(vals),
               "z_top": max(v[2] for v in vals), "vz_spout": sum(v[3] for v in vals) / len(vals),
               "wall_s": wall, "outputs": len(vals)}
        row["spouts"] = row["fountain_min"] >= args.min_fountain
        rows.append(row)
        print("spout_onset:   fountain %.1f particles (min %d over %d outputs), H_s %.1f mm, "
              "highest centre %.1f mm, spout vz %.3f m/s: %s (%.0f s wall)" % (
                  mean_f, row["fountain_min"], len(vals), 1e3 * row["h_s"], 1e3 * row["z_top"],
                  row["vz_spout"], "spouting" if row["spouts"] else "NOT spouting", wall),
              flush=True)
        prev = folder
        if not row["spouts"] and not args.all:
            break

    lines = ["# Minimum spouting velocity: %s" % os.path.relpath(args.case, os.getcwd()), "",
             "Decreasing jet velocity from a stable spout; %d rank(s); first level %d steps, then "
             "%d steps a level; a level spouts when every output of its second half holds >= %g "
             "particles more than %g d above the annulus surface in the central half." % (
                 args.ranks, args.spinup_steps, args.level_steps, args.min_fountain, args.above),
             "", "| jet (m/s) | column superficial (m/s) | fountain (mean / min) | annulus surface "
             "(mm) | highest centre (mm) | spout vz (m/s) | spouting | wall (s) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %.2f | %.3f | %.1f / %d | %.1f | %.1f | %.3f | %s | %.0f |" % (
            r["u_jet"], r["u_column"], r["fountain"], r["fountain_min"], 1e3 * r["h_s"],
            1e3 * r["z_top"], r["vz_spout"], "yes" if r["spouts"] else "no", r["wall_s"]))
    yes = [r for r in rows if r["spouts"]]
    no = [r for r in rows if not r["spouts"]]
    lines.append("")
    if yes and no:
        lo, hi = no[0]["u_jet"], yes[-1]["u_jet"]
        lines.append("Measured U_ms: the spout collapses between jet %.2f and %.2f m/s: U_ms = "
                     "%.2f +- %.2f m/s at the slot, %.3f +- %.3f m/s over the column." % (
                         lo, hi, 0.5 * (lo + hi), 0.5 * (hi - lo), 0.5 * (lo + hi) * area_ratio,
                         0.5 * (hi - lo) * area_ratio))
    elif yes:
        lines.append("Measured U_ms: below %.2f m/s at the slot (every level spouted)." %
                     yes[-1]["u_jet"])
    else:
        lines.append("No level spouted: raise the first velocity or --spinup-steps.")
    lines += ["", "Mathur-Gishler, H = %.3f m, d_p = %.4f m (slot / column area %.4f):" % (
        args.bed_height, d_p, area_ratio), "",
              "| diameters | D_c (m) | D_i (m) | U_ms column (m/s) | jet equivalent (m/s) |",
              "|---|---|---|---|---|"]
    for name, dc, di, u, uj in correlations(case, geo, args.bed_height):
        lines.append("| %s | %.4f | %.4f | %.3f | %.1f |" % (name, dc, di, u, uj))
    text = "\n".join(lines) + "\n"
    print(text)
    with open(os.path.join(args.out, "spout_onset.md"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()

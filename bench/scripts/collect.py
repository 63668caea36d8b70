#!/usr/bin/python3
"""Many run folders of a scaling campaign -> one CSV of the figures scaling plots use.

    bench/scripts/collect.py out/case3-np* --out case3.csv        # the folders named
    bench/scripts/collect.py --find out/campaign --out all.csv    # every report.json below

One row per run (its `coloc run --out` folder, read with the `coloc` Python module,
bench/python/coloc): where it ran (case, mode, strategy, ranks, nodes, ranks a node, cores used,
oversubscribed, binding, yield_when_idle, host, commit), what it measured (steps of this run, wall
and set-up seconds, s_per_step, each phase's seconds a step over the ranks, average and
maximum: s_per_step_<phase> and s_per_step_<phase>_max, the shares of the step, load imbalance,
throughputs and the figure of merit, inter-physics bytes and messages, peak memory), and the
strong-scaling inputs: within each group of runs of the same case, mode, strategy and cells
(a `--group-by` of report key paths replaces it), `base_ranks` (its fewest ranks),
`base_s_per_step` (the fastest run at those ranks), `speedup` = base_s_per_step / s_per_step and
`efficiency` = speedup x base_ranks / ranks.

Runs whose report says other than "ok" (failed, interrupted) are left out and named on stderr
(--all keeps them, without speedup). Exit status 0 when the CSV is written, 1 when no run was
found, 2 for a bad command line.
"""
import argparse
import csv
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))  # bench/python or share/coloc/python
import coloc  # noqa: E402

FIXED = ["folder", "case", "name", "status", "mode", "strategy", "ranks", "nodes",
         "ranks_per_node_max", "cores_used", "oversubscribed", "binding", "yield_when_idle",
         "cells", "particles", "steps", "wall_s", "setup_s", "s_per_step", "frac_fv", "frac_dem",
         "frac_coupling", "frac_inter_physics", "frac_wait", "imbalance", "cell_steps_per_s",
         "particle_steps_per_s", "particle_steps_per_s_per_core", "cell_steps_per_s_per_core",
         "inter_remote_bytes", "inter_remote_messages", "inter_local_bytes", "intra_bytes",
         "peak_rss_bytes_sum", "host", "date", "git_commit"]
SCALING = ["group", "base_ranks", "base_s_per_step", "speedup", "efficiency"]


def find_runs(roots):
    """Every folder holding a report.json below the roots."""
    out = []
    for root in roots:
        for d, _, files in os.walk(root):
            if "report.json" in files:
                out.append(d)
    return sorted(out)


def row_of(run):
    g = run.get
    steps = (g("run.steps", 0) or 0) - (g("run.first_step", 0) or 0)
    wall = g("run.wall_s", 0.0) or 0.0
    cells = g("config.domain.cells")
    row = {
        "folder": run.folder, "case": run.report.get("case"), "name": g("config.name"),
        "status": run.status, "mode": g("run.mode"), "strategy": g("partition.strategy"),
        "ranks": g("mpi.ranks"), "nodes": g("provenance.nodes"),
        "ranks_per_node_max": g("provenance.ranks_per_node_max"),
        "cores_used": g("provenance.cores_used"), "oversubscribed": g("provenance.oversubscribed"),
        "binding": g("provenance.mpi_env.binding"),
        "yield_when_idle": g("provenance.mpi_env.yield_when_idle"),
        "cells": "x".join(str(c) for c in cells) if isinstance(cells, list) else cells,
        "particles": g("particles.count", 0), "steps": steps, "wall_s": wall,
        "setup_s": g("run.setup_s"), "s_per_step": wall / steps if steps > 0 else None,
        "frac_fv": g("fractions.fv"), "frac_dem": g("fractions.dem"),
        "frac_coupling": g("fractions.coupling"), "frac_inter_physics": g("fractions.inter_physics"),
        "frac_wait": g("fractions.wait"), "imbalance": g("load.imbalance"),
        "cell_steps_per_s": g("throughput.cell_steps_per_s"),
        "particle_steps_per_s": g("throughput.particle_steps_per_s"),
        "particle_steps_per_s_per_core": g("figure_of_merit.particle_steps_per_s_per_core"),
        "cell_steps_per_s_per_core": g("figure_of_merit.cell_steps_per_s_per_core"),
        "inter_remote_bytes": g("exchange.inter_physics_remote.bytes"),
        "inter_remote_messages": g("exchange.inter_physics_remote.messages"),
        "inter_local_bytes": g("exchange.inter_physics_local.bytes"),
        "intra_bytes": g("exchange.intra_physics.bytes"),
        "peak_rss_bytes_sum": g("memory.peak_rss_bytes_sum"), "host": g("provenance.host"),
        "date": g("provenance.date"), "git_commit": g("provenance.git_commit"),
    }
    phases = {}
    for phase, t in sorted((run.report.get("timers") or {}).items()):
        if phase == "setup" or not isinstance(t, dict) or steps <= 0:
            continue
        phases["s_per_step_" + phase] = t.get("avg", 0.0) / steps
        phases["s_per_step_%s_max" % phase] = t.get("max", 0.0) / steps
    return row, phases


def add_scaling(rows, group_by):
    """speedup and efficiency against the fastest run at the fewest ranks of each group."""
    groups = {}
    for r in rows:
        if r["status"] != "ok" or not r["s_per_step"]:
            continue
        key = tuple("x".join(map(str, v)) if isinstance(v, list) else str(v)
                    for v in (r["_keys"][k] for k in group_by))
        groups.setdefault(key, []).append(r)
    for key, members in groups.items():
        n0 = min(m["ranks"] for m in members)
        t0 = min(m["s_per_step"] for m in members if m["ranks"] == n0)
        for m in members:
            m["group"] = "/".join(key)
            m["base_ranks"] = n0
            m["base_s_per_step"] = t0
            m["speedup"] = t0 / m["s_per_step"]
            m["efficiency"] = m["speedup"] * n0 / m["ranks"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 epilog=__doc__.split("\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folders", nargs="*", help="run folders (each with its report.json)")
    ap.add_argument("--find", action="append", default=[], metavar="DIR",
                    help="every folder with a report.json below DIR (repeatable)")
    ap.add_argument("--out", "-o", default="-", help="the CSV (default: standard output)")
    ap.add_argument("--all", action="store_true", help="keep runs that did not end 'ok'")
    ap.add_argument("--group-by", nargs="+", metavar="KEY",
                    default=["case", "run.mode", "partition.strategy", "config.domain.cells"],
                    help="report key paths that make a scaling group (default: case, run.mode, "
                         "partition.strategy, config.domain.cells)")
    args = ap.parse_args(argv)
    folders = list(args.folders) + find_runs(args.find)
    if not folders:
        ap.print_usage(sys.stderr)
        print("collect.py: error: no run folder given (FOLDERS or --find DIR)", file=sys.stderr)
        return 2
    rows, phase_names = [], []
    for d in folders:
        try:
            run = coloc.read_run(d)
        except (OSError, ValueError) as e:
            print("collect.py: skipped %s: %s" % (d, e), file=sys.stderr)
            continue
        if run.status != "ok" and not args.all:
            print("collect.py: skipped %s: status %s" % (d, run.status), file=sys.stderr)
            continue
        row, phases = row_of(run)
        row.update(phases)
        row["_keys"] = {k: coloc.report_value(run.report, k, "") for k in args.group_by}
        for p in phases:
            if p not in phase_names:
                phase_names.append(p)
        rows.append(row)
    if not rows:
        print("collect.py: error: no run to collect", file=sys.stderr)
        return 1
    add_scaling(rows, args.group_by)
    rows.sort(key=lambda r: (str(r.get("group", "")), r["ranks"] or 0, r["folder"]))
    fields = FIXED + SCALING + sorted(phase_names)
    out = sys.stdout if args.out == "-" else open(args.out, "w", newline="")
    w = csv.DictWriter(out, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in fields})
    if out is not sys.stdout:
        out.close()
        print("collect.py: %d runs -> %s" % (len(rows), args.out), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""A calibrated performance MODEL of coloc's coupled step at rank counts that are not run.

time per step of rank r = unit costs measured on 1 rank (report.json timers)
                          x the rank's work from `coloc plan` (plan.json)
                          x the memory-bandwidth contention of the ranks sharing its node
                        + the pressure solve's per-level and per-iteration latencies
                        + its messages through a latency-bandwidth network model.

Unit costs (seconds from a 1-rank run of the same physics; wall, or thread-CPU with --busy):
  fluid          per cell-step (momentum, boundaries, projection, cell fields);
  pressure set-up per cell-step (fluid_pressure_assemble: right-hand side and matrix), and per
                 cell and set-up (fluid_pressure_setup: hypre's PCG+PFMG set-up) x the set-ups a
                 step (report.pressure.setups / steps: 1 / fluid.pressure.setup_interval in a
                 long run; reports before the split book both in the first, one set-up a step);
  pressure solve per cell and PCG iteration, x the iterations per step of the 1-rank run;
  hypre's overhead per PFMG level and face neighbour (per iteration, per set-up) that 1 rank
                 cannot show: bench_fv BM_PressureSolve on cubes (--overhead-grid own: on the
                 case's grid, BM_PressureSolveBox) at 1 and 2 ranks (--pfmg1, --pfmg2);
  DEM            per particle and sub-step (contacts folded in);
  coupling       per particle-step on the rank's coupled particles (own, or proxies).
Memory term (bench_stream, --stream): B(k) = the triad bandwidth ONE rank gets while k ranks of a
  node stream at once; contention c(k) = B(1) / B(k), at the working set (of those measured)
  where two ranks contend most. Each phase group g has a memory-bound share m_g, measured by
  re-running the 1-rank calibration beside a co-runner streaming that working set (--corun):
  slowdown s_g = t_g(with co-runner) / t_g(alone), m_g = (s_g - 1) / (c(2) - 1) in [0, 1]. At P
  ranks with n = min(P, ranks a node) on each node, group g costs t_g x (1 + m_g (c(n) - 1)).
Pressure solve latency per PCG iteration: levels x 7 halo exchanges (V(1,1): 2 red-black
  half-sweeps before and after, residual, restriction, interpolation) + 1 (matrix-vector
  product), each one message to each face neighbour; 3 allreduces (latency x ceil(log2 P)); the
  bytes of one layer of p on the fine level, twice (coarse levels). Per set-up: levels x 2
  exchanges (coarse operators). levels = 1 + sum_d ceil(log2 n_d) (PFMG semi-coarsening).
Network per rank and step, per traffic kind of plan.json (bytes, messages):
  t = messages * latency + bytes / bandwidth_per_rank,
  bandwidth_per_rank = link bandwidth / min(ranks, ranks a node sharing the injection).
Noise (bench_noise, --noise): the same work runs unevenly on the cores of a real machine (a
  shared host, frequency changes, the hypervisor); eta(P) = the expected extra time of the
  slowest of P ranks doing equal work, a fraction of that work, measured for a compute kernel
  (pair loop) and a memory one (triad at the stream working set); group g's eta mixes them by
  its memory share m_g. Each rank's work of group g costs eta_g more at the slowest rank: inside
  the pressure solve and set-up that is fluid time (waited for at hypre's collectives), elsewhere
  it is waited for at a barrier (wait). Beyond the measured ranks eta grows as the expected
  maximum of P independent draws of the measured relative times (extrapolated). No noise unless
  measured: the cluster profiles assume dedicated, quiet cores.
Independent strategy: the handover of particle rows inside a rank (force_handover bytes) at
  memory speed, unless the calibration is a 1-rank run of that strategy: then its exchange_local
  time per handover byte (handover_per_byte_s, a gather and scatter of rows) is charged on the
  handover and the proxy bytes alike, the network on top for the proxies.
Shares: fluid = fluid work + pressure + fluid halos; DEM = DEM work + ghost updates; coupling =
coupling arithmetic; inter-physics = deposit sum + proxies (+ the independent strategy's
handover, above); wait = step - mean rank time. The step is the slowest rank's time
plus the noise.

Usage:
  model.py calibrate [--busy] REPORT_1RANK.json [--corun REPORT_1RANK_CORUN.json
                     --stream stream.json] [--pfmg1 fv1.json --pfmg2 fv2.json
                     --pingpong pingpong.json] > costs.json
  model.py predict --costs costs.json --plan plan.json [plan2.json ...] --profile edr-ib|PINGPONG.json
                   [--stream stream.json] [--noise noise-*.json ...] [--csv out.csv]
                   [--png out.png] [--title T]
  model.py plot --csv out.csv --png out.png [--title T]     # re-draw the figure from its CSV
Validation at 1 and 2 ranks: bench/scripts/validate_model.py.
"""
import argparse
import csv
import json
import math
import os
import re
import sys
import textwrap

import provenance  # bench/scripts/provenance.py: the stamp on every plot

# the calibration (unit costs, memory shares, hypre's overhead, noise) and the names both sides
# share live in bench/scripts/model_calibrate.py; re-exported here for the scripts that import
# them from model (validate_model.py, smpi_scaling.py, test_model.py)
from model_calibrate import (  # noqa: F401
    ALLREDUCES_PER_ITER, EXCH_PER_ITER, EXCH_PER_LEVEL, EXCH_PER_SETUP_LEVEL, GROUPS,
    bench_points, calibrate, calibrate_median, contention, fit_contention_overhead, grid_levels,
    group_times, median, median_of, median_stream, noise_of, solver_overhead, stream_memory,
    stream_size, timer)

PROFILES = {
    # EDR InfiniBand: ~1 us, ~12 GB/s per link, 28 ranks a node sharing the injection bandwidth.
    # Memory (ASSUMPTION, no such node measured here): a dual-socket 14-core Xeon E5-2680 v4
    # node, 8 channels of DDR4-2400 = 153.6 GB/s peak; STREAM triad ~110 GB/s a node, ~12 GB/s
    # for one core alone: c(n) = max(1, 12 n / 110) -> 3.05 at 28 ranks a node.
    "edr-ib": {"latency_s": 1.0e-6, "bandwidth_Bps": 12.0e9, "ranks_per_node": 28,
               "memory_Bps": 10.0e9,
               "memory": {"core_Bps": 12.0e9, "node_Bps": 110.0e9, "ranks_per_node": 28}},
}


def expected_max_excess(quantiles, n):
    """E[max of n independent draws] - E[draw] of the distribution given by equally spaced
    quantiles (each point carrying the same weight)."""
    q = sorted(quantiles)
    N = len(q)
    if N == 0 or n <= 1:
        return 0.0
    emax = sum(q[i] * (((i + 1) / N) ** n - (i / N) ** n) for i in range(N))
    return emax - sum(q) / N


def noise_eta(spec, P):
    """eta(P) of one noise spec: the measured figure where P ranks were measured; beyond, the
    largest measured figure grown as the expected maximum of P independent draws of the measured
    relative times grows (an EXTRAPOLATION: independent ranks)."""
    if not spec or P <= 1:
        return 0.0
    by = {int(k): v for k, v in spec["by_ranks"].items()}
    if P in by:
        return by[P]
    k = max(kk for kk in by if kk <= P) if any(kk <= P for kk in by) else min(by)
    g_k = expected_max_excess(spec.get("quantiles", []), k)
    g_p = expected_max_excess(spec.get("quantiles", []), P)
    return by[k] * g_p / g_k if g_k > 0 else by[k]


def profile(spec, stream=None):
    """A network profile: a name of PROFILES, or this machine's ping-pong (bench_pingpong's JSON,
    as a path or as the loaded dict)."""
    if isinstance(spec, str) and spec in PROFILES:
        prof = dict(PROFILES[spec], name=spec)
    else:
        p = spec
        if not isinstance(spec, dict):
            with open(spec) as f:
                p = json.load(f)
        # this machine: the measured ping-pong, all ranks on one node (shared memory)
        prof = {"latency_s": p["latency_s"], "bandwidth_Bps": p["bandwidth_Bps"],
                "ranks_per_node": 1, "memory_Bps": p["bandwidth_Bps"], "name": "this machine",
                "memory": None}
    if stream is not None:
        prof["memory"] = stream_memory(stream)
        prof["name"] += " + measured stream"
    prof.setdefault("noise", None)  # dedicated, quiet cores unless a measured noise is given
    return prof


def neighbours(dims, r):
    """Face neighbours of rank r of a non-periodic dims grid (MPI_Cart order, last axis
    fastest)."""
    c = [0, 0, 0]
    for a in (2, 1, 0):
        c[a] = r % dims[a]
        r //= dims[a]
    return sum((c[a] > 0) + (c[a] < dims[a] - 1) for a in range(3) if dims[a] > 1)


def box_face_neighbours(boxes, r):
    """Face neighbours of box r among general boxes [lo_x, lo_y, lo_z, hi_x, hi_y, hi_z] (the
    tiled strategy): the boxes sharing a face of positive area with it (no periodic images, as
    neighbours() for Cartesian blocks)."""
    b = boxes[r]
    n = 0
    for q, o in enumerate(boxes):
        if q == r:
            continue
        for a in range(3):
            if b[3 + a] != o[a] and o[3 + a] != b[a]:
                continue
            if all(min(b[3 + e], o[3 + e]) > max(b[e], o[e]) for e in range(3) if e != a):
                n += 1
                break
    return n


def pfmg_levels(layout):
    if "boxes" in layout:  # tiled: the global grid is the boxes' union
        return grid_levels([max(b[3 + a] for b in layout["boxes"]) for a in range(3)])
    return grid_levels([cuts[-1] for cuts in layout["fluid_cuts"]])


def predict_layout(costs, layout, prof, setups_per_step=None):
    P = layout["ranks"]
    pr = layout["per_rank"]
    ks = pr["per_step"]
    sub = layout["dem_substeps_per_step"]
    indep = layout["strategy"] == "independent"
    share = min(P, prof["ranks_per_node"]) if prof["ranks_per_node"] > 1 else 1
    bw = prof["bandwidth_Bps"] / share
    lat = prof["latency_s"]
    mem = prof.get("memory")
    node = min(P, mem["ranks_per_node"]) if mem else 1
    c = contention(mem, node)
    ms = costs.get("memory_share", {})
    f = {g: 1.0 + ms.get(g, 0.0) * (c - 1.0) for g in GROUPS}
    iters = costs["pressure_iterations_per_step"]
    # hypre's set-ups a step: the calibration run's, or the caller's (fluid.pressure.setup_interval
    # keeps a set-up for up to that many steps: 1 / interval in a long run)
    setups = costs.get("pressure_setups_per_step", 1.0) if setups_per_step is None else setups_per_step
    ov = costs.get("pressure_overhead", {})
    o_it = ov.get("per_level_neighbour_iteration_s", 0.0)
    o_su = ov.get("per_level_neighbour_setup_s", 0.0)
    levels = pfmg_levels(layout)
    logp = math.ceil(math.log2(P)) if P > 1 else 0
    dims = layout.get("fluid_dims")
    boxes = layout.get("boxes")

    def net(kind, r):
        return ks[kind]["messages"][r] * lat + ks[kind]["bytes"][r] / bw

    noise = prof.get("noise") or {}
    eta_c, eta_m = noise_eta(noise.get("compute"), P), noise_eta(noise.get("memory"), P)
    eta = {g: (1 - ms.get(g, 0.0)) * eta_c + ms.get(g, 0.0) * eta_m
           if noise.get("memory") else eta_c for g in GROUPS}
    rows, lost = [], []
    for r in range(P):
        cells, parts = pr["cells"][r], pr["particles"][r]
        coupled = pr["proxies"][r] if indep else parts
        nb = 0 if P == 1 else (box_face_neighbours(boxes, r) if boxes else neighbours(dims, r))
        fluid = cells * costs["fluid_per_cell_step"] * f["fluid"]
        psetup = (cells * (costs.get("pressure_setup_per_cell_step", 0.0) +
                           setups * costs.get("pressure_hypre_setup_per_cell", 0.0)) *
                  f["pressure_setup"] + setups * levels * nb * o_su)
        if "pressure_hypre_setup_per_cell" not in costs:  # costs of before the split: per set-up
            psetup = setups * (cells * costs.get("pressure_setup_per_cell_step", 0.0) *
                               f["pressure_setup"] + levels * nb * o_su)
        psolve = iters * (cells * costs["pressure_per_cell_iteration"] * f["pressure_solve"] +
                          levels * nb * o_it)
        halo_p = pr["ghost_cells"][r] / 2 * 8  # one layer of p on the fine level
        per_iter = ((levels * EXCH_PER_LEVEL + EXCH_PER_ITER) * nb * lat +
                    ALLREDUCES_PER_ITER * lat * logp +
                    2 * (EXCH_PER_LEVEL + EXCH_PER_ITER) * halo_p / bw)
        pressure_net = iters * per_iter + setups * levels * EXCH_PER_SETUP_LEVEL * nb * lat
        fluid_net = net("fluid_halo", r) + net("coupling_halo", r) + pressure_net
        dem = parts * sub * costs["dem_per_particle_substep"] * f["dem"]
        dem_net = net("dem_ghost", r)
        cpl = coupled * costs["coupling_per_particle_step"] * f["coupling"]
        inter = net("deposit_sum", r) + net("proxy", r)
        if indep and "handover_per_byte_s" in costs:
            # every row is gathered and its force scattered, whether it stays in the rank or
            # travels: the calibrated per-byte cost on both, the network on top for the proxies
            inter += ((ks["force_handover"]["bytes"][r] + ks["proxy"]["bytes"][r]) *
                      costs["handover_per_byte_s"])
        elif indep:
            inter += ks["force_handover"]["bytes"][r] / prof["memory_Bps"]
        rows.append((fluid + psetup + psolve + fluid_net, dem + dem_net, cpl, inter,
                     psetup + psolve + pressure_net))
        # the machine's noise: the slowest rank's extra time on the same work, eta of each
        # group; inside the pressure solve (waited for at hypre's own collectives) it is fluid
        # time, elsewhere it is waited for at a barrier (wait)
        lost.append((eta["pressure_setup"] * psetup + eta["pressure_solve"] * psolve,
                     eta["fluid"] * fluid + eta["dem"] * dem + eta["coupling"] * cpl))
    tot = [sum(x[:4]) for x in rows]
    mean = [sum(x[i] for x in rows) / P for i in range(5)]
    in_solve = sum(x[0] for x in lost) / P
    at_barriers = sum(x[1] for x in lost) / P
    step = max(tot) + in_solve + at_barriers
    mean[0] += in_solve
    mean[4] += in_solve
    busy = sum(mean[:4])
    return {"strategy": layout["strategy"], "ranks": P, "step_s": step,
            "fluid": mean[0] / step, "dem": mean[1] / step, "coupling": mean[2] / step,
            "inter_physics": mean[3] / step, "wait": 1 - busy / step,
            "imbalance": step / busy if busy > 0 else 1.0,
            "pressure": mean[4] / step, "memory_contention": c,
            "noise": {"compute": eta_c, "memory": eta_m} if noise else None,
            "noise_wait": at_barriers / step,
            "fluid_of_busy": mean[0] / busy, "dem_of_busy": mean[1] / busy,
            "coupling_of_busy": mean[2] / busy, "inter_physics_of_busy": mean[3] / busy}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    sp = ap.add_subparsers(dest="cmd", required=True)
    c = sp.add_parser("calibrate")
    c.add_argument("report")
    c.add_argument("--busy", action="store_true",
                   help="fit thread-CPU (busy) times instead of wall: on a shared, loaded machine")
    c.add_argument("--corun", help="report of the same 1-rank run beside bench_stream --co-run")
    c.add_argument("--stream", help="bench_stream JSON (with --corun: the memory-bound shares)")
    c.add_argument("--pfmg1", help="bench_fv --benchmark_format=json, BM_PressureSolve/n/0 "
                   "on 1 rank")
    c.add_argument("--pfmg2", help="the same on 2 ranks (hypre's per-level, per-neighbour cost)")
    c.add_argument("--pingpong", help="latency the network model adds (taken off the overhead)")
    c.add_argument("--overhead-grid", choices=["cubes", "own"], default="cubes",
                   help="hypre's overhead from the cubes (default) or the case's own grid")
    p = sp.add_parser("predict")
    p.add_argument("--costs", required=True)
    p.add_argument("--plan", required=True, nargs="+",
                   help="plan.json of `coloc plan`; several: their layouts together")
    p.add_argument("--profile", required=True)
    p.add_argument("--stream", help="bench_stream JSON: this machine's memory contention")
    p.add_argument("--noise", nargs="+", help="bench_noise JSONs (kernels pairs and triad, "
                   "repeats): this machine's noise; default none (dedicated cores)")
    p.add_argument("--csv")
    p.add_argument("--png")
    p.add_argument("--title", default="")
    q = sp.add_parser("plot", help="re-draw predict's figure from its --csv")
    q.add_argument("--csv", required=True)
    q.add_argument("--png", required=True)
    q.add_argument("--title", default="", help="the case's name in the title (default: the CSV's)")
    a = ap.parse_args()
    if a.cmd == "plot":
        with open(a.csv) as f:
            head = f.readline()
            rows = list(csv.DictReader(f))
        m = re.match(r"# MODEL \(bench/scripts/model.py\), profile (.*), costs from (.*)$",
                     head.strip())
        prof_name, source = (m.group(1), m.group(2)) if m else ("?", "?")
        for r in rows:
            for k in r:
                if k != "strategy":
                    r[k] = float(r[k])
        draw(rows, a.png, a.title or os.path.splitext(os.path.basename(a.csv))[0], prof_name,
             source, data_files=[a.csv], extra="MODEL, re-drawn from its CSV")
        return
    if a.cmd == "calibrate":
        def load(path):
            if not path:
                return None
            with open(path) as f:
                return json.load(f)
        pp = load(a.pingpong)
        costs = calibrate(load(a.report), "busy_avg" if a.busy else "avg", load(a.corun),
                          load(a.stream), load(a.pfmg1), load(a.pfmg2),
                          pp["latency_s"] if pp else 0.0, a.overhead_grid)
        json.dump(costs, sys.stdout, indent=1)
        print()
        return
    with open(a.costs) as f:
        costs = json.load(f)
    plan = None
    for path in a.plan:
        with open(path) as f:
            p = json.load(f)
        if plan is None:
            plan = p
        else:  # the 1-rank layout once (the speedup's reference)
            plan["layouts"] += [L for L in p["layouts"] if L["ranks"] > 1]
    stream = None
    if a.stream:
        with open(a.stream) as f:
            stream = json.load(f)
    prof = profile(a.profile, stream)
    if a.noise:
        runs = []
        for path in a.noise:
            with open(path) as f:
                runs.append(json.load(f))
        prof["noise"] = noise_of(runs)
        prof["name"] += " + measured noise"
    out = [predict_layout(costs, L, prof) for L in plan["layouts"] if "error" not in L]
    # speedup against one rank's modelled time (the serial work: sum of the work of all ranks)
    serial = None
    for r in out:
        if r["ranks"] == 1:
            serial = r["step_s"]
    keys = ["strategy", "ranks", "step_s", "speedup", "fluid", "dem", "coupling", "inter_physics",
            "wait", "imbalance", "pressure", "memory_contention", "fluid_of_busy", "dem_of_busy",
            "coupling_of_busy",
            "inter_physics_of_busy"]
    for r in out:
        r["speedup"] = serial / r["step_s"] if serial else float("nan")
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("# MODEL (bench/scripts/model.py), profile " + prof["name"] + ", costs from " +
                    costs["source"] + "\n" + ",".join(keys) + "\n")
            for r in out:
                f.write(",".join(str(r[k]) if isinstance(r[k], str) else "%.6g" % r[k]
                                 for k in keys) + "\n")
    print("MODEL, profile %s, costs from %s" % (prof["name"], costs["source"]))
    print("%-12s %6s %11s %8s %7s %7s %7s %7s %7s %6s" % ("strategy", "ranks", "step (s)",
          "speedup", "fluid", "dem", "coupl", "inter", "wait", "imb"))
    for r in out:
        print("%-12s %6d %11.4g %8.1f %6.1f%% %6.1f%% %6.1f%% %6.2f%% %6.1f%% %6.2f" % (
            r["strategy"], r["ranks"], r["step_s"], r["speedup"], 100 * r["fluid"], 100 * r["dem"],
            100 * r["coupling"], 100 * r["inter_physics"], 100 * r["wait"], r["imbalance"]))
    if a.png:
        cost_run = provenance.of_report(costs) if costs.get("provenance") else None
        draw(out, a.png, a.title or plan["case"], prof["name"], costs["source"],
             reports=[costs] if cost_run else [],
             data_files=[] if cost_run else [a.costs],
             extra="MODEL computed from these unit costs")


def draw(out, png, title, prof_name, source, reports=(), data_files=(), extra="MODEL"):
    """predict's figure: speedup, inter-physics share and the fluid / DEM / wait shares against
    ranks, stamped: a MODEL, computed where drawn, from the unit costs' run (reports) or the
    files given."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    for s in sorted({r["strategy"] for r in out}):
        rs = [r for r in out if r["strategy"] == s]
        P = [r["ranks"] for r in rs]
        ax[0].loglog(P, [r["speedup"] for r in rs], "o-", label=s)
        ax[1].semilogx(P, [100 * r["inter_physics"] for r in rs], "o-", label=s)
        ax[2].semilogx(P, [100 * r["fluid"] for r in rs], "o-", label=s + " fluid")
        ax[2].semilogx(P, [100 * r["dem"] for r in rs], "s--", label=s + " DEM")
        ax[2].semilogx(P, [100 * r["wait"] for r in rs], "^:", label=s + " wait")
    ax[0].set_ylabel("speedup (vs 1 rank)")
    ax[1].set_ylabel("inter-physics exchange (% of step)")
    ax[2].set_ylabel("% of step")
    for x in ax:
        x.set_xlabel("ranks")
        x.grid(True, which="both", alpha=0.3)
        x.legend(fontsize=7)
    fig.suptitle("\n".join(textwrap.wrap(
        "MODEL (not measured): %s, profile %s, unit costs from %s" % (title, prof_name, source),
        170)))
    fig.tight_layout()
    provenance.stamp(fig, reports=reports, data_files=data_files, extra=extra)
    provenance.savefig(fig, png, dpi=110)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""A calibrated performance MODEL of coloc's coupled step at rank counts that are not run.

time per step of rank r = unit costs measured on 1 rank (report.json timers)
                          x the rank's work from `coloc plan` (plan.json)
                          x the memory-bandwidth contention of the ranks sharing its node
                        + the pressure solve's per-level and per-iteration latencies
                        + its messages through a latency-bandwidth network model.

Unit costs (seconds from a 1-rank run of the same physics; wall, or thread-CPU with --busy):
  fluid          per cell-step (momentum, boundaries, projection, cell fields);
  pressure set-up per cell-step (fluid_pressure_assemble: right-hand side, matrix and, where the
                 coefficients change, hypre's PCG+PFMG set-up; report.pressure.setups counts them);
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
Shares: fluid = fluid work + pressure + fluid halos; DEM = DEM work + ghost updates; coupling =
coupling arithmetic; inter-physics = deposit sum + proxies (+ in-rank copies of the independent
strategy at memory speed); wait = step - mean rank time. The step is the slowest rank's time
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

GROUPS = {
    "fluid": ["fluid_momentum", "fluid_boundary", "fluid_project", "fluid_cell_fields"],
    "pressure_setup": ["fluid_pressure_assemble"],
    "pressure_solve": ["fluid_pressure_solve"],
    # dem_migrate: packing the contact histories and moving particles at a rebuild (on 1 rank
    # all compute; its messages are not in the first step's plan)
    "dem": ["dem_neighbor", "dem_force", "dem_integrate", "dem_migrate"],
    "coupling": ["coupling_deposit", "coupling_interpolate", "coupling_drag"],
}
EXCH_PER_LEVEL = 7   # PFMG V(1,1), symmetric red-black relaxation
EXCH_PER_ITER = 1    # PCG matrix-vector product
ALLREDUCES_PER_ITER = 3  # PCG: (r, z), (p, Ap), the two-norm of r
EXCH_PER_SETUP_LEVEL = 2
PROFILES = {
    # EDR InfiniBand: ~1 us, ~12 GB/s per link, 28 ranks a node sharing the injection bandwidth.
    # Memory (ASSUMPTION, no such node measured here): a dual-socket 14-core Xeon E5-2680 v4
    # node, 8 channels of DDR4-2400 = 153.6 GB/s peak; STREAM triad ~110 GB/s a node, ~12 GB/s
    # for one core alone: c(n) = max(1, 12 n / 110) -> 3.05 at 28 ranks a node.
    "edr-ib": {"latency_s": 1.0e-6, "bandwidth_Bps": 12.0e9, "ranks_per_node": 28,
               "memory_Bps": 10.0e9,
               "memory": {"core_Bps": 12.0e9, "node_Bps": 110.0e9, "ranks_per_node": 28}},
}


def timer(report, name, key):
    return report["timers"].get(name, {}).get(key, 0.0)


def group_times(report, key):
    return {g: sum(timer(report, n, key) for n in names) for g, names in GROUPS.items()}


def contention(mem, n):
    """c(n) = B(1) / B(n): how much slower a memory-bound loop runs with n ranks of a node."""
    if n <= 1 or not mem:
        return 1.0
    if "per_rank_Bps" in mem:
        b = mem["per_rank_Bps"]
        if n <= len(b):
            return b[0] / b[n - 1]
        node = max((k + 1) * x for k, x in enumerate(b))
        return max(b[0] / b[-1], b[0] * n / node)
    return max(1.0, mem["core_Bps"] * n / mem["node_Bps"])


def stream_size(stream):
    """Index of the working set where two ranks contend most (the co-runner streams at it)."""
    b = stream["per_rank_Bps"]
    if stream["ranks"] < 2:
        return len(b) - 1
    return max(range(len(b)), key=lambda i: b[i][0] / b[i][1])


def stream_memory(stream):
    """The memory spec of a bench_stream JSON, at its most contended working set."""
    i = stream_size(stream)
    return {"per_rank_Bps": stream["per_rank_Bps"][i], "ranks_per_node": stream["ranks"],
            "size_mib": stream["sizes_mib"][i], "loadavg": stream.get("loadavg", "")}


def median(xs):
    """The median of a non-empty list (the mean of the middle two for an even count)."""
    v = sorted(xs)
    m = len(v) // 2
    return v[m] if len(v) % 2 else 0.5 * (v[m - 1] + v[m])


def median_of(items):
    """Element-wise median of equally shaped JSON-like values (dicts, lists, numbers); a leaf
    that is not a number (or is missing in some) is taken from the first item."""
    first = items[0]
    if isinstance(first, bool) or not isinstance(first, (dict, list, int, float)):
        return first
    if isinstance(first, dict):
        return {k: median_of([it[k] for it in items if isinstance(it, dict) and k in it])
                for k in first}
    if isinstance(first, list):
        if not all(isinstance(it, list) and len(it) == len(first) for it in items):
            return first
        return [median_of([it[i] for it in items]) for i in range(len(first))]
    nums = [it for it in items if isinstance(it, (int, float)) and not isinstance(it, bool)]
    return median(nums) if nums else first


def median_stream(streams):
    """One bench_stream JSON from several runs: the median bandwidth of each rank count and
    working set (the memory contention of one run moves with the machine's load)."""
    out = dict(streams[0])
    out["per_rank_Bps"] = median_of([s["per_rank_Bps"] for s in streams])
    out["repeats"] = len(streams)
    out["loadavg"] = "; ".join(str(s.get("loadavg", "")) for s in streams)
    return out


def bench_points(bench, busy, how="min"):
    """BM_PressureSolve/n/0 and BM_PressureSolveBox/nx/ny/nz/0 (bench_fv,
    --benchmark_format=json): {("cube" | "box", nx, ny, nz): (seconds per PCG iteration, set-up
    seconds, ranks)};
    thread-CPU times with busy; of --benchmark_repetitions the fastest (how="min") or the
    median (how="median")."""
    reps = {}
    for b in bench.get("benchmarks", []):
        parts = b["name"].split("/")
        if b.get("run_type") == "aggregate":
            continue
        if parts[0] == "BM_PressureSolve" and parts[2] == "0":
            n = ("cube",) + (int(parts[1]),) * 3
        elif parts[0] == "BM_PressureSolveBox" and parts[4] == "0":
            n = ("box",) + tuple(int(x) for x in parts[1:4])
        else:
            continue
        unit = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[b.get("time_unit", "ns")]
        t = b["cpu_time" if busy else "real_time"] * unit
        its = max(b["iterations"], 1)  # the PCG counter: written after Google Benchmark's own
        setup = b.get("setup_cpu_s", b["setup_s"]) if busy else b["setup_s"]
        reps.setdefault(n, []).append((t / its, setup, int(b["ranks"])))
    agg = min if how == "min" else median
    return {n: (agg([r[0] for r in v]), agg([r[1] for r in v]), v[0][2]) for n, v in reps.items()}


def grid_levels(dims):
    """PFMG levels of a global grid: 1 + sum_d ceil(log2 n_d) (one axis coarsened a level)."""
    return 1 + sum(math.ceil(math.log2(n)) for n in dims if n > 1)


def fit_contention_overhead(points):
    """Least squares of t2 = f t1 / 2 + L o over points (t1, t2, L) of different sizes, each
    equation scaled by 1 / t2 (the sizes' times differ tenfold): the memory contention f of the
    solve at 2 ranks and hypre's overhead o a level and neighbour, f >= 1, o >= 0. None where
    fewer than two sizes (or levels) are given: f and o are then not separable."""
    if len({p[2] for p in points}) < 2:
        return None
    a11 = a12 = a22 = b1 = b2 = 0.0
    for t1, t2, L in points:
        x, y = t1 / 2 / t2, L / t2
        a11, a12, a22 = a11 + x * x, a12 + x * y, a22 + y * y
        b1, b2 = b1 + x, b2 + y  # right-hand side t2 / t2 = 1
    det = a11 * a22 - a12 * a12
    if det <= 0:
        return None
    f = (b1 * a22 - b2 * a12) / det
    o = (a11 * b2 - a12 * b1) / det
    if o < 0:  # no overhead: f alone
        o, f = 0.0, b1 / a11
    if f < 1:  # no contention: o alone
        f = 1.0
        o = max(0.0, sum((t2 - t1 / 2) / L for t1, t2, L in points) / len(points))
    return f, o


def solver_overhead(costs, one, two, busy, latency, grid=None, use_own=False, how="min"):
    """hypre's cost per PFMG level and face neighbour that a 1-rank run cannot show (comm
    packages, packing, the coarse levels' halos), per PCG iteration and per set-up: from
    bench_fv's pressure solve at 1 and 2 ranks (2 x 1 x 1: one neighbour). With cubes of two
    sizes or more (BM_PressureSolve/32 and /64: a cached and a memory-bound one), the memory
    contention f of the solve at 2 ranks and the overhead o are fitted together,
    t(2 ranks) = f t(1 rank) / 2 + levels o (fit_contention_overhead), and f gives the solve's
    memory share (calibrate). With one point, f = 1 + m (c(2) - 1) from the co-run's memory share
    m: o = (t(2 ranks) - f t(1 rank) / 2) / levels, a difference of two close numbers that moves
    with m (docs/plan.md). Either way the message latencies the network model adds itself are
    taken off o. grid="own" takes the point on the case's own grid instead
    (BM_PressureSolveBox), with the co-run's m."""
    p1, p2 = bench_points(one, busy, how), bench_points(two, busy, how)
    c2 = costs.get("memory_calibration", {}).get("contention_2", 1.0)
    ms = costs["memory_share"]
    f_it = 1 + ms["pressure_solve"] * (c2 - 1)
    f_su = 1 + ms["pressure_setup"] * (c2 - 1)
    both = [n for n in sorted(set(p1) & set(p2)) if p1[n][2] == 1 and p2[n][2] == 2]
    own = ("box",) + tuple(grid) if grid is not None and use_own else None
    if own in both:
        both = [own]
    else:
        both = [n for n in both if n[0] == "cube"]
    if not both:
        return None
    levels = {n: grid_levels(n[1:]) for n in both}
    fit_it = fit_contention_overhead([(p1[n][0], p2[n][0], levels[n]) for n in both])
    fit_su = fit_contention_overhead([(p1[n][1], p2[n][1], levels[n]) for n in both])
    o_it, o_su, used = [], [], []
    for n in both:
        L = levels[n]
        o_it.append(max(0.0, p2[n][0] - f_it * p1[n][0] / 2) / L)
        o_su.append(max(0.0, p2[n][1] - f_su * p1[n][1] / 2) / L)
        used.append([list(n[1:]), p1[n][0], p2[n][0], p1[n][1], p2[n][1]])
    raw_it = fit_it[1] if fit_it else sum(o_it) / len(o_it)
    raw_su = fit_su[1] if fit_su else sum(o_su) / len(o_su)
    # the latencies the network model adds: (levels x 7 + 1) halos and 3 allreduces an
    # iteration, levels x 2 halos a set-up (one neighbour, log2(2) = 1)
    lat_it = sum((EXCH_PER_LEVEL + 1) * latency + ALLREDUCES_PER_ITER * latency / levels[n]
                 for n in both) / len(both)
    out = {"per_level_neighbour_iteration_s": max(0.0, raw_it - lat_it),
           "per_level_neighbour_setup_s": max(0.0, raw_su - EXCH_PER_SETUP_LEVEL * latency),
           "from": "the case's own grid" if own in both else "cubes",
           "points_grid_iter1_iter2_setup1_setup2": used}
    if fit_it:
        out["contention_2_iteration"] = fit_it[0]
    if fit_su:
        out["contention_2_setup"] = fit_su[0]
    out["fit"] = ("contention and overhead fitted together over %d sizes" % len(both)
                  if fit_it or fit_su else "overhead at the co-run's contention")
    return out


def calibrate(report, key="avg", corun=None, stream=None, pfmg1=None, pfmg2=None, latency=0.0,
              overhead_grid="cubes", how="min"):
    # a restarted run's timers cover its own steps, its counters (steps, DEM sub-steps, pressure
    # set-ups) the whole history since the original start: per step, they are the same
    total = report["run"]["steps"]
    steps = total - report["run"].get("first_step", 0)
    sub = report["run"]["dem_substeps"] * steps / total if total else 0
    cells = 1
    for c in report["config"]["domain"]["cells"]:
        cells *= c
    n = report["particles"]["count"] if "particles" in report else 0
    pres = report.get("pressure", {})
    iters = pres.get("iterations_avg", 0.0) * steps
    tg = group_times(report, key)
    frozen = report.get("particles", {}).get("frozen", False)
    costs = {
        "source": report["case"] if isinstance(report["case"], str) else str(report["case"]),
        # the 1-rank run the unit costs come from (stamped on the model's figures)
        "provenance": report.get("provenance"),
        "cells": cells,
        "fluid_per_cell_step": tg["fluid"] / (cells * steps),
        "pressure_setup_per_cell_step": tg["pressure_setup"] / (cells * steps),
        "pressure_setups_per_step": pres.get("setups", total) / total,
        "pressure_per_cell_iteration": tg["pressure_solve"] / (cells * iters) if iters > 0 else 0.0,
        "pressure_iterations_per_step": iters / steps,
        "dem_per_particle_substep": 0.0 if frozen or sub == 0 or n == 0 else tg["dem"] / (n * sub),
        "coupling_per_particle_step": tg["coupling"] / (n * steps) if n else 0.0,
        "timer": "wall" if key == "avg" else "busy (thread CPU)",
        "measured_step_s": report["run"]["wall_s"] / steps,
        "measured_busy_step_s": report["load"]["busy_s_max"] / steps,
        "measured_fractions": report["fractions"],
        "memory_share": {g: 0.0 for g in GROUPS},
        "pressure_overhead": {"per_level_neighbour_iteration_s": 0.0,
                              "per_level_neighbour_setup_s": 0.0},
    }
    if corun is not None and stream is not None:
        c2 = contention(stream_memory(stream), 2)  # c2 - 1 < 0.05: nothing to measure against
        tc = group_times(corun, key)
        csteps = corun["run"]["steps"] - corun["run"].get("first_step", 0)
        slow = {}
        for g in GROUPS:
            if tg[g] > 0 and tc[g] > 0:
                slow[g] = (tc[g] / csteps) / (tg[g] / steps)
                costs["memory_share"][g] = (min(1.0, max(0.0, (slow[g] - 1) / (c2 - 1)))
                                            if c2 > 1.05 else 0.0)
        costs["memory_calibration"] = {"contention_2": c2, "slowdown_with_corunner": slow,
                                       "stream_loadavg": stream.get("loadavg", "")}
    if pfmg1 is not None and pfmg2 is not None:
        o = solver_overhead(costs, pfmg1, pfmg2, key != "avg", latency,
                            report["config"]["domain"]["cells"], overhead_grid == "own", how)
        if o:
            costs["pressure_overhead"] = o
            # the solve's own contention from the cubes replaces the co-run's share for the
            # pressure groups: they are a few per cent of a coupled step, so a co-run barely
            # shows them (its share of the solve moved 0.04-0.45 between repeats)
            c2 = costs.get("memory_calibration", {}).get("contention_2", 1.0)
            for g, k in (("pressure_solve", "contention_2_iteration"),
                         ("pressure_setup", "contention_2_setup")):
                if k in o and c2 > 1.05:
                    costs["memory_share"][g] = min(1.0, max(0.0, (o[k] - 1) / (c2 - 1)))
                    costs.setdefault("memory_share_from", {})[g] = "bench_fv cubes (%s)" % k
    return costs


def calibrate_median(reports, key="avg", coruns=None, stream=None, pfmg1=None, pfmg2=None,
                     latency=0.0, overhead_grid="cubes"):
    """The median of repeated calibrations: one calibration from each 1-rank run (with the
    co-run of the same repeat, when there is one), each unit cost, memory share and overhead the
    median over the repeats; the benchmarks' repetitions by their median too. One disturbed run
    then moves no input (a single calibration's inputs move between runs as much as the model's
    tolerance: docs/plan.md, "Repeatability")."""
    coruns = coruns or []
    each = [calibrate(r, key, coruns[i] if i < len(coruns) else None, stream, pfmg1, pfmg2,
                      latency, overhead_grid, "median") for i, r in enumerate(reports)]
    costs = median_of(each)
    costs["repeats"] = len(each)
    return costs


def noise_of(runs):
    """The machine's noise from bench_noise JSONs (one a repeat, kernel pairs or triad; both
    counts for either): {"compute": spec, "memory": spec}, spec = {"by_ranks": {k: eta(k)},
    "quantiles": [...], "repeats": n}, each figure the median over the repeats. eta(k) = the
    expected wait for the slowest of k ranks doing the same work, a fraction of the mean work."""
    out = {}
    for name, kernels in (("compute", ("pairs", "both")), ("memory", ("triad", "both"))):
        rs = [r for r in runs if r.get("kernel", "both") == kernels[0]]
        rs = rs or [r for r in runs if r.get("kernel", "both") == kernels[1]]
        if not rs:
            continue
        ks = sorted({b["ranks"] for r in rs for b in r["by_ranks"]})
        by = {}
        for k in ks:
            v = [b["noise"] for r in rs for b in r["by_ranks"] if b["ranks"] == k]
            by[str(k)] = median(v)
        q = [r["relative_time_quantiles"] for r in rs if r.get("relative_time_quantiles")]
        out[name] = {"by_ranks": by, "quantiles": median_of(q) if q else [],
                     "repeats": len(rs), "mib": rs[0].get("mib", 0.0)}
    return out


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


def predict_layout(costs, layout, prof):
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
    setups = costs.get("pressure_setups_per_step", 1.0)
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
        if indep:
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

"""The CALIBRATION side of the performance model (bench/scripts/model.py): the timer groups of a
report.json (GROUPS) and the pressure solve's message counts, then everything that turns measured
runs into the model's inputs: the unit costs of a 1-rank run and the memory-bound shares from its
co-run (calibrate, calibrate_median), bench_stream's memory contention (contention,
stream_memory, median_stream), hypre's per-level overhead from bench_fv at 1 and 2 ranks
(bench_points, fit_contention_overhead, solver_overhead) and the machine's noise from bench_noise
(noise_of). model.py re-exports every name here, so scripts keep importing them from model;
`model.py calibrate` is the command line.
"""
import math

GROUPS = {
    "fluid": ["fluid_momentum", "fluid_boundary", "fluid_project", "fluid_cell_fields"],
    # the pressure matrix and right-hand side every step, and hypre's set-up where one is made
    # (fluid_pressure_setup, nested in the assembly; reports before it booked both in one timer)
    "pressure_setup": ["fluid_pressure_assemble", "fluid_pressure_setup"],
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
        # the assembly a cell and step, and hypre's set-up a cell and set-up (reports without the
        # set-up's own timer: all of it in the first, one set-up a step)
        "pressure_setup_per_cell_step": timer(report, "fluid_pressure_assemble", key) / (cells * steps),
        "pressure_hypre_setup_per_cell": (timer(report, "fluid_pressure_setup", key) /
                                          (cells * max(1.0, pres.get("setups", total) * steps / total))),
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
    # The independent strategy's handover (each particle's row gathered for the fluid's side,
    # its force scattered back), per byte, from a 1-rank run of that strategy: there every row
    # stays in the rank (exchange_local, force_handover bytes). A gather of rows, not a copy at
    # stream speed: 0.76 ns a byte on case3-small against 0.1 ns at 10 GB/s (docs/smpi.md).
    handover = report.get("exchange_kinds", {}).get("force_handover", {}).get("bytes", 0)
    local = report.get("timers", {}).get("exchange_local", {}).get(key, 0.0)
    if handover > 0 and local > 0:
        costs["handover_per_byte_s"] = local / handover
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

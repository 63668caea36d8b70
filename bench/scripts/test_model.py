#!/usr/bin/env python3
"""Unit test of bench/scripts/model.py and validate_model.py on a tiny synthetic calibration
(no MPI, no coloc run; deterministic). Every expected number is worked out by hand below; the
test exits 1 on the first mismatch. CTest: model_unit (label unit)."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import model  # noqa: E402

FAILS = []


def check(what, got, want, rel=1e-9):
    if not (abs(got - want) <= rel * max(abs(want), 1e-300)):
        FAILS.append("%s: got %.12g, want %.12g" % (what, got, want))


def report(steps, group_s, ranks=1, busy_max=None, iters=2.0, setups=None):
    """A report.json with the given per-group seconds (wall and busy alike)."""
    tm = {}
    for g, names in model.GROUPS.items():
        for n in names[:1]:
            tm[n] = {"avg": group_s.get(g, 0.0), "busy_avg": group_s.get(g, 0.0), "calls": steps}
    total = sum(group_s.values())
    return {"case": "synthetic", "config": {"domain": {"cells": [10, 10, 10]}},
            "run": {"steps": steps, "dem_substeps": 0, "wall_s": total},
            "particles": {"count": 100, "frozen": True},
            "pressure": {"iterations_avg": iters, "setups": steps if setups is None else setups},
            "timers": tm, "load": {"busy_s_max": busy_max if busy_max else total},
            "fractions": {"fv": 0.9, "dem": 0.0, "coupling": 0.1, "inter_physics": 0.0,
                          "wait": 0.0}}


def layout(P):
    cells = [1000 // P] * P
    zero = {"bytes": [0] * P, "messages": [0] * P}
    per_step = {k: dict(zero) for k in ("fluid_halo", "coupling_halo", "dem_ghost", "dem_migrate",
                                        "deposit_sum", "proxy", "force_handover")}
    return {"strategy": "uniform", "ranks": P, "fluid_dims": [P, 1, 1],
            "fluid_cuts": [[0, 10] if P == 1 else [0, 5, 10], [0, 10], [0, 10]],
            "dem_substeps_per_step": 0,
            "per_rank": {"cells": cells, "particles": [100 // P] * P, "proxies": [0] * P,
                         "ghost_cells": [0 if P == 1 else 200] * P, "per_step": per_step}}


def main():
    # --- contention: measured table, then extrapolation with the node's best total bandwidth
    mem = {"per_rank_Bps": [10e9, 5e9], "ranks_per_node": 2}
    check("c(1)", model.contention(mem, 1), 1.0)
    check("c(2)", model.contention(mem, 2), 2.0)
    check("c(4) extrapolated", model.contention(mem, 4), 10e9 * 4 / 10e9)
    check("c(28) edr-ib", model.contention(model.PROFILES["edr-ib"]["memory"], 28), 12 * 28 / 110)
    # --- geometry
    check("neighbours 2x1x1 rank 0", model.neighbours([2, 1, 1], 0), 1)
    check("neighbours 3x3x3 centre", model.neighbours([3, 3, 3], 13), 6)
    check("neighbours 3x3x3 corner", model.neighbours([3, 3, 3], 0), 3)
    # tiled boxes on 4x4x1 cells: a left half and two right quarters; an edge contact is no face
    tiled = [[0, 0, 0, 2, 4, 1], [2, 0, 0, 4, 2, 1], [2, 2, 0, 4, 4, 1]]
    check("box neighbours left half", model.box_face_neighbours(tiled, 0), 2)
    check("box neighbours quarter", model.box_face_neighbours(tiled, 1), 2)
    diag = [[0, 0, 0, 2, 2, 1], [2, 2, 0, 4, 4, 1], [2, 0, 0, 4, 2, 1], [0, 2, 0, 2, 4, 1]]
    check("box neighbours: corner contact is none", model.box_face_neighbours(diag, 0), 2)
    check("PFMG levels of boxes", model.pfmg_levels({"boxes": tiled}), 1 + 2 + 2)
    check("PFMG levels 10^3", model.pfmg_levels(layout(2)), 1 + 3 * 4)

    # --- calibration: 10 steps, 1000 cells; fluid 0.010 s, set-up 0.004 s, solve 0.002 s
    # (2 iterations a step -> 20 iterations), coupling 0.001 s; with the co-runner fluid is 1.5x
    # (m = 0.5 at c(2) = 2), the solve 2x (m = 1), coupling 1x (m = 0).
    alone = {"fluid": 0.010, "pressure_setup": 0.004, "pressure_solve": 0.002, "coupling": 0.001}
    co = {"fluid": 0.015, "pressure_setup": 0.004, "pressure_solve": 0.004, "coupling": 0.001}
    stream = {"ranks": 2, "sizes_mib": [192.0], "per_rank_Bps": [[10e9, 5e9]]}
    # bench_fv on a 16^3 cube (levels 1 + 3*4 = 13): 1 rank 1.0 ms an iteration, 2 ranks
    # (solve m = 1: f = 2, so the per-cell part stays 1.0 ms) 1.0 ms + 13 x 10 us; set-up
    # 10 ms / (f = 1) 5 ms + 13 x 20 us. Latency 1 us is taken off: o = 10 - 8 - 3/13 us.
    # Each with a slower repetition and an aggregate row, which must not count.
    def fv(ranks, it, su):
        def row(k, kind="iteration"):
            return {"name": "BM_PressureSolve/16/0/iterations:3/manual_time",
                    "run_type": kind, "iterations": 4, "time_unit": "ms",
                    "real_time": 4 * k * it * 1e3, "cpu_time": 4 * k * it * 1e3,
                    "cells": 4096, "ranks": ranks, "setup_s": k * su, "setup_cpu_s": k * su}
        return {"benchmarks": [row(1.7), row(1.0), row(1.3), row(0.5, "aggregate")]}
    o_it, o_su = 10e-6, 20e-6
    c = model.calibrate(report(10, alone), "busy_avg", report(10, co), stream,
                        fv(1, 1e-3, 10e-3), fv(2, 1e-3 + 13 * o_it, 5e-3 + 13 * o_su), 1e-6)
    check("fluid per cell-step", c["fluid_per_cell_step"], 0.010 / 10000)
    check("setup per cell-step", c["pressure_setup_per_cell_step"], 0.004 / 10000)
    check("solve per cell-iteration", c["pressure_per_cell_iteration"], 0.002 / 20000)
    check("coupling per particle-step", c["coupling_per_particle_step"], 0.001 / 1000)
    check("m fluid", c["memory_share"]["fluid"], 0.5)
    check("m solve", c["memory_share"]["pressure_solve"], 1.0)
    check("m setup", c["memory_share"]["pressure_setup"], 0.0)
    check("m coupling", c["memory_share"]["coupling"], 0.0)
    ov = c["pressure_overhead"]
    check("overhead per iteration", ov["per_level_neighbour_iteration_s"],
          o_it - 8e-6 - 3e-6 / 13)
    check("overhead per set-up", ov["per_level_neighbour_setup_s"], o_su - 2e-6)

    # a point on the case's own grid (BM_PressureSolveBox/10/10/10: levels 13) wins over the
    # cubes: here 3 us a level and neighbour more than the 16^3 cube's
    def fvbox(ranks, it, su):
        r = fv(ranks, it, su)["benchmarks"][1]
        return dict(r, name="BM_PressureSolveBox/10/10/10/0/iterations:3/manual_time")
    def both(ranks, it, su, itb, sub):
        return {"benchmarks": fv(ranks, it, su)["benchmarks"] + [fvbox(ranks, itb, sub)]}
    cb = model.calibrate(report(10, alone), "busy_avg", report(10, co), stream,
                         both(1, 1e-3, 10e-3, 1e-3, 10e-3),
                         both(2, 1e-3 + 13 * o_it, 5e-3 + 13 * o_su, 1e-3 + 13 * (o_it + 3e-6),
                              5e-3 + 13 * o_su), 1e-6, "own")
    ob = cb["pressure_overhead"]
    check("own-grid overhead per iteration", ob["per_level_neighbour_iteration_s"],
          o_it + 3e-6 - 8e-6 - 3e-6 / 13)
    check("own-grid point named", ob["from"] == "the case's own grid", True)
    cc = model.calibrate(report(10, alone), "busy_avg", report(10, co), stream,
                         both(1, 1e-3, 10e-3, 1e-3, 10e-3),
                         both(2, 1e-3 + 13 * o_it, 5e-3 + 13 * o_su, 1e-3 + 13 * (o_it + 3e-6),
                              5e-3 + 13 * o_su), 1e-6)
    check("default: the cubes", cc["pressure_overhead"]["per_level_neighbour_iteration_s"],
          o_it - 8e-6 - 3e-6 / 13)

    # --- a restarted run (first_step 600, 10 steps timed): its counters (steps, DEM sub-steps,
    # pressure set-ups) count from the original start, its timers its own 10 steps; per step
    # the same as a fresh run's
    rr = report(10, dict(alone, dem=0.002))
    rr["run"].update(steps=610, first_step=600, dem_substeps=6100)
    rr["pressure"]["setups"] = 610
    rr["particles"]["frozen"] = False
    cr = model.calibrate(rr, "busy_avg")
    check("restart: set-ups a step", cr["pressure_setups_per_step"], 1.0)
    check("restart: DEM per particle-sub-step", cr["dem_per_particle_substep"],
          0.002 / (100 * 100))
    check("restart: fluid per cell-step", cr["fluid_per_cell_step"], 0.010 / 10000)

    # --- contention and overhead fitted together from cubes of two sizes: 16^3 (levels 13) and
    # 32^3 (levels 16), exact data made with f = 1.5 and o = 10 us (an iteration), f = 1.25 and
    # o = 20 us (a set-up): the fit returns them exactly; c(2) = 2 gives the solve's memory share
    # m = (f - 1) / (c(2) - 1) = 0.5 (set-up 0.25), which replaces the co-run's
    f_fit, o_fit = model.fit_contention_overhead([(1e-3, 1.5 * 0.5e-3 + 13 * 10e-6, 13),
                                                  (8e-3, 1.5 * 4e-3 + 16 * 10e-6, 16)])
    check("fit: contention", f_fit, 1.5)
    check("fit: overhead", o_fit, 10e-6)
    check("fit: one size is not separable",
          model.fit_contention_overhead([(1e-3, 1e-3, 13)]) is None, True)
    # made with f = 0.9 (faster at 2 ranks than half of 1: no contention to fit): f = 1, and o
    # the mean of (t2 - t1 / 2) / L: (-0.05 + 0.65) / 13 ms and (-0.4 + 0.8) / 16 ms
    f0, o0 = model.fit_contention_overhead([(1e-3, 0.9 * 0.5e-3 + 13 * 50e-6, 13),
                                            (8e-3, 0.9 * 4e-3 + 16 * 50e-6, 16)])
    check("fit: f clamped at 1", f0, 1.0)
    check("fit: then o alone", o0, 0.5 * (0.6e-3 / 13 + 0.4e-3 / 16))

    def cubes(ranks, f_it, f_su):
        out = []
        for n, L, it1, su1 in ((16, 13, 1e-3, 10e-3), (32, 16, 8e-3, 80e-3)):
            it = it1 if ranks == 1 else f_it * it1 / 2 + L * o_it
            su = su1 if ranks == 1 else f_su * su1 / 2 + L * o_su
            out.append({"name": "BM_PressureSolve/%d/0/iterations:3/manual_time" % n,
                        "run_type": "iteration", "iterations": 4, "time_unit": "ms",
                        "real_time": 4 * it * 1e3, "cpu_time": 4 * it * 1e3, "ranks": ranks,
                        "setup_s": su, "setup_cpu_s": su})
        return {"benchmarks": out}
    cf = model.calibrate(report(10, alone), "busy_avg", report(10, co), stream, cubes(1, 0, 0),
                         cubes(2, 1.5, 1.25), 1e-6)
    of = cf["pressure_overhead"]
    check("fitted contention of the solve", of["contention_2_iteration"], 1.5)
    check("fitted contention of the set-up", of["contention_2_setup"], 1.25)
    check("fitted overhead, latencies off", of["per_level_neighbour_iteration_s"],
          o_it - 8e-6 - 0.5 * (3e-6 / 13 + 3e-6 / 16))
    check("fitted set-up overhead", of["per_level_neighbour_setup_s"], o_su - 2e-6)
    check("solve's memory share from the cubes", cf["memory_share"]["pressure_solve"], 0.5)
    check("set-up's memory share from the cubes", cf["memory_share"]["pressure_setup"], 0.25)
    check("fluid's memory share still the co-run's", cf["memory_share"]["fluid"], 0.5)

    # --- the machine's noise: quantiles 0.9, 1.0, 1.1 (equal weights): E[max of 2] =
    # (0.9 + 3 x 1.0 + 5 x 1.1) / 9, E[max of 4] = (0.9 + 15 x 1.0 + 65 x 1.1) / 81
    q = [0.9, 1.0, 1.1]
    check("E[max of 2] - mean", model.expected_max_excess(q, 2), 9.4 / 9 - 1.0)
    check("E[max of 4] - mean", model.expected_max_excess(q, 4), 87.4 / 81 - 1.0)
    nz = model.noise_of([
        {"kernel": "pairs", "mib": 0, "by_ranks": [{"ranks": 2, "noise": x}],
         "relative_time_quantiles": q} for x in (0.05, 0.02, 0.03)] + [
        {"kernel": "triad", "mib": 48, "by_ranks": [{"ranks": 2, "noise": 0.1}],
         "relative_time_quantiles": q}])
    check("noise: median of the repeats", nz["compute"]["by_ranks"]["2"], 0.03)
    check("noise: repeats", nz["compute"]["repeats"], 3)
    check("eta(1) = 0", model.noise_eta(nz["compute"], 1), 0.0)
    check("eta(2) measured", model.noise_eta(nz["compute"], 2), 0.03)
    check("eta(4) extrapolated", model.noise_eta(nz["compute"], 4),
          0.03 * (87.4 / 81 - 1) / (9.4 / 9 - 1))

    # --- the median of repeats: the benchmarks' repetitions (1.7, 1.0, 1.3: median 1.3, min
    # 1.0), and one calibration a 1-rank run, each input the median over them
    pm = model.bench_points(fv(1, 1e-3, 10e-3), True, "median")[("cube", 16, 16, 16)]
    check("median repetition, iteration", pm[0], 1.3e-3)
    check("median repetition, set-up", pm[1], 1.3 * 10e-3)
    check("min repetition", model.bench_points(fv(1, 1e-3, 10e-3), True)[("cube", 16, 16, 16)][0],
          1.0e-3)
    check("median of even count", model.median([4.0, 1.0, 3.0, 2.0]), 2.5)
    mo = model.median_of([{"a": [1.0, 5.0], "b": "x"}, {"a": [3.0, 2.0], "b": "y"},
                          {"a": [2.0, 9.0], "b": "z"}])
    check("median_of list 0", mo["a"][0], 2.0)
    check("median_of list 1", mo["a"][1], 5.0)
    check("median_of keeps text", mo["b"] == "x", True)
    slow = dict(alone, fluid=3 * alone["fluid"])  # one disturbed run of three
    cm = model.calibrate_median([report(10, alone), report(10, slow), report(10, alone)],
                                "busy_avg", [report(10, co)] * 3, stream,
                                fv(1, 1e-3, 10e-3), fv(2, 1e-3 + 13 * o_it, 5e-3 + 13 * o_su),
                                1e-6)
    check("median calibration: the disturbed run moves nothing", cm["fluid_per_cell_step"],
          0.010 / 10000)
    check("median calibration: memory share", cm["memory_share"]["fluid"], 0.5)
    check("median calibration: repeats", cm["repeats"], 3)
    ms = model.median_stream([{"per_rank_Bps": [[4.0, 2.0]], "loadavg": "a"},
                              {"per_rank_Bps": [[5.0, 1.0]], "loadavg": "b"},
                              {"per_rank_Bps": [[6.0, 3.0]], "loadavg": "c"}])
    check("median stream", ms["per_rank_Bps"][0][1], 2.0)

    # --- prediction at 1 rank reproduces the calibration; at 2 ranks, by hand
    prof = {"latency_s": 1e-6, "bandwidth_Bps": 1e9, "ranks_per_node": 1, "memory_Bps": 1e9,
            "name": "t", "memory": mem}
    p1 = model.predict_layout(c, layout(1), prof)
    check("1 rank step", p1["step_s"], 0.0017)
    p2 = model.predict_layout(c, layout(2), prof)
    fluid = 500 * 1e-6 * 1.5
    setup = 500 * 4e-7 + 13 * ov["per_level_neighbour_setup_s"] + 13 * 2 * 1e-6
    halo_p = 100 * 8
    solve = 2 * (500 * 1e-7 * 2 + 13 * ov["per_level_neighbour_iteration_s"] +
                 (13 * 7 + 1) * 1e-6 + 3 * 1e-6 * 1 + 2 * 8 * halo_p / 1e9)
    cpl = 50 * 1e-6
    check("2 rank step", p2["step_s"], fluid + setup + solve + cpl)
    check("2 rank coupling share", p2["coupling"], cpl / (fluid + setup + solve + cpl))
    check("2 rank contention", p2["memory_contention"], 2.0)

    # --- the independent strategy's handover: a 1-rank run of it gives 0.5 ns a byte (0.02 s
    # of exchange_local over 10 steps for 4e7 handover bytes); at 2 ranks each rank gathers
    # 1e6 bytes for itself and 1e6 for the other rank, which also cross the network (1 GB/s,
    # 2 messages)
    ri = report(10, alone)
    ri["timers"]["exchange_local"] = {"avg": 0.02, "busy_avg": 0.02, "calls": 10}
    ri["exchange_kinds"] = {"force_handover": {"bytes": 4e7}}
    ci = model.calibrate(ri, "avg")
    check("handover per byte", ci["handover_per_byte_s"], 0.02 / 4e7)
    li = layout(2)
    li["strategy"] = "independent"
    li["per_rank"]["proxies"] = [50, 50]
    li["per_rank"]["per_step"]["force_handover"] = {"bytes": [1e6, 1e6], "messages": [0, 0]}
    li["per_rank"]["per_step"]["proxy"] = {"bytes": [1e6, 1e6], "messages": [2, 2]}
    pi = model.predict_layout(ci, li, prof)
    inter_i = 2e6 * 0.5e-9 + 2 * 1e-6 + 1e6 / 1e9
    check("independent inter-physics, calibrated handover", pi["inter_physics"] * pi["step_s"],
          inter_i)
    pu = model.predict_layout(c, li, prof)  # no handover in the calibration: memory speed
    check("independent inter-physics, memory speed", pu["inter_physics"] * pu["step_s"],
          1e6 / 1e9 + 2 * 1e-6 + 1e6 / 1e9)

    # --- with the machine's noise: eta(2) = 0.04 (compute), 0.10 (memory); each group's eta
    # mixes them by its memory share (fluid 0.5: 0.07; solve 1: 0.10; set-up 0: 0.04; coupling
    # 0: 0.04). The solve's and set-up's extra time is fluid time, the rest is wait.
    profn = dict(prof, noise={"compute": {"by_ranks": {"2": 0.04}, "quantiles": []},
                              "memory": {"by_ranks": {"2": 0.10}, "quantiles": []}})
    pn = model.predict_layout(c, layout(2), profn)
    psetup = 500 * 4e-7 + 13 * ov["per_level_neighbour_setup_s"]
    psolve = 2 * (500 * 1e-7 * 2 + 13 * ov["per_level_neighbour_iteration_s"])
    in_solve = 0.04 * psetup + 0.10 * psolve
    at_barriers = 0.07 * fluid + 0.04 * cpl
    stepn = fluid + setup + solve + cpl + in_solve + at_barriers
    check("noise: step", pn["step_s"], stepn)
    check("noise: wait", pn["wait"], at_barriers / stepn)
    check("noise: fluid share", pn["fluid"], (fluid + setup + solve + in_solve) / stepn)
    check("noise: none at 1 rank", model.predict_layout(c, layout(1), profn)["step_s"], 0.0017)

    # --- validate: a 2-rank point 5 % off passes, 25 % off fails (--strict exit code)
    base = tempfile.mkdtemp(prefix="coloc-model-test-")
    try:
        # the third: with the machine's noise (bench_noise files, eta 0.05 for both kernels) and
        # the ping-pong measured with the runs (pingpong-0.json; --pingpong then names a file
        # 1000x slower, which must not be read): the model adds 0.05 x (set-up + solve) to the
        # fluid and 0.05 x (fluid + coupling) as wait, and the synthetic run holds exactly that
        for off, want_rc, noisy in ((1.05, 0, False), (1.25, 1, False), (1.0, 0, True)):
            d = os.path.join(base, "x%.2f%s" % (off, "-noise" if noisy else ""))
            os.makedirs(os.path.join(d, "synthetic", "plan"))
            with open(os.path.join(d, "stream.json"), "w") as f:
                json.dump(stream, f)
            with open(os.path.join(d, "synthetic", "plan", "plan.json"), "w") as f:
                json.dump({"layouts": [layout(1), layout(2)]}, f)
            pp = os.path.join(d, "pingpong.json")
            with open(pp, "w") as f:
                json.dump({"latency_s": 1e-3 if noisy else 1e-6, "bandwidth_Bps": 1e9}, f)
            in_solve = at_barriers = 0.0
            if noisy:
                with open(os.path.join(d, "pingpong-0.json"), "w") as f:
                    json.dump({"latency_s": 1e-6, "bandwidth_Bps": 1e9}, f)
                for kern in ("pairs", "triad"):
                    with open(os.path.join(d, "synthetic", "noise-%s-0.json" % kern), "w") as f:
                        json.dump({"kernel": kern, "mib": 1.0, "relative_time_quantiles": q,
                                   "by_ranks": [{"ranks": 2, "noise": 0.05}]}, f)
                in_solve = 0.05 * (500 * 4e-7 + 2 * 500 * 1e-7 * 2)
                at_barriers = 0.05 * (500 * 1e-6 * 1.5 + cpl)
            # no bench_fv files here: the overhead is 0; predicted 2-rank step by hand
            want = (500 * 1e-6 * 1.5 + 500 * 4e-7 + 13 * 2 * 1e-6 +
                    2 * (500 * 1e-7 * 2 + 92 * 1e-6 + 3e-6 + 16 * 800 / 1e9) + cpl +
                    in_solve + at_barriers)
            two = {g: 0.0 for g in alone}
            two["fluid"] = (want - cpl - at_barriers) * off * 10
            two["coupling"] = cpl * off * 10
            np2 = report(10, two, ranks=2, busy_max=want * off * 10)
            for k, r in (("np1-0", report(10, alone)), ("np1corun-0", report(10, co)),
                         ("np2-0", np2)):
                os.makedirs(os.path.join(d, "synthetic", k))
                with open(os.path.join(d, "synthetic", k, "report.json"), "w") as f:
                    json.dump(r, f)
            rc = subprocess.run([sys.executable, os.path.join(HERE, "validate_model.py"),
                                 "--reports", d, "--cases", "synthetic.json", "--pingpong", pp,
                                 "--out", os.path.join(d, "out"), "--strict"],
                                capture_output=True, text=True)
            if rc.returncode != want_rc:
                FAILS.append("validate with the 2-rank point x%.2f: exit %d, want %d\n%s%s" %
                             (off, rc.returncode, want_rc, rc.stdout, rc.stderr))
            txt = open(os.path.join(d, "out", "validate-synthetic.txt")).read()
            line = [x for x in txt.splitlines() if x.startswith("2 ") and "step_s" in x][0]
            err = float(line.split()[4].rstrip("%"))
            if abs(err - 100 * (1 / off - 1)) > 0.06:  # printed to 0.1 %
                FAILS.append("validate step error x%.2f: %g %%" % (off, err))
            if noisy:
                wl = [x for x in txt.splitlines() if x.startswith("2 ") and " wait " in x][0]
                if abs(float(wl.split()[2].rstrip("%")) - 100 * at_barriers / want) > 0.06 or \
                        abs(float(wl.split()[4].rstrip("pt"))) > 0.06:
                    FAILS.append("validate with noise, the wait: %s" % wl)
                if "median of 1 during the runs" not in txt or "eta(2) = 0.0500" not in txt:
                    FAILS.append("validate with noise: ping-pong or noise not read\n" + txt)
    finally:
        shutil.rmtree(base)
    if FAILS:
        print("FAIL\n" + "\n".join(FAILS))
        return 1
    print("model.py: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

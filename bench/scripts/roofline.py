#!/usr/bin/env python3
"""Each kernel of coloc against its own limit: a roofline table from a run's report.json.

    build/bench/bench_peak --benchmark_out=peak.json --benchmark_out_format=json
    mpirun -n 1 build/bench/bench_stream --mib 1 --mib 3 --mib 12 --mib 24 --mib 48 --mib 96 \\
        --mib 256 --json stream.json
    BED=$(bench/scripts/dense_bed.py bench/cases/case3-small.json)
    build/coloc run bench/cases/case3-small.json --set "$BED" --set run.steps=10 --out R
    build/coloc run bench/cases/case3-small.json --set "$BED" --set run.steps=3 \\
        --set particles.skin=1e-6 --out RB        # optional: a list rebuild every sub-step
    bench/scripts/roofline.py --report R/report.json --peak peak.json [--stream stream.json] \\
        [--rebuild-report RB/report.json] [--markdown | --json]

bench/results/roofline/ holds a measured set and its table (docs/benchmarks.md, "Each kernel
against its own limit"). The report must be of a fresh run (not a restart): the timers cover
the loop, and `particles.rebuilds` the rebuilds of the whole run.

For each kernel (KERNELS below): the bytes and flops of one pass, counted from the code (the terms,
each a count of the report times bytes and flops per item; `where` names the functions counted),
its time from the report's busy timer, and the one-core ceilings measured by bench_peak:
  peak    the flop/s of the instruction set the kernel is compiled for (mul and add separate:
          the DEM is compiled with -ffp-contract=off and the portable build has no FMA), or FMA
          where the kernel's code uses it (SLEEF's AVX-512 functions in the drag law);
  bw      the triad bandwidth of one core at the kernel's working set (its compulsory bytes a
          pass; for the pressure solve, whose iterations re-read the same data, one copy of it),
          interpolated in log(size) between the sizes measured (bench_peak BM_Triad, or
          bench_stream's one-rank row with --stream): a working set inside the caches is bounded
          by the cache's bandwidth, not DRAM's;
  bound   min(peak, AI x bw) / (flops per unit), units/s; AI = flops / bytes.
  achieved  units / (busy seconds); fraction = achieved / bound; `binds` says which ceiling is
          lower (memory or compute).
Bytes are compulsory: every array a pass reads once (8 B a double, 4 B an int) plus every array
it writes once (a read-modify-write counts both); no write-allocate, no re-reads of gathered
lines, no cache misses beyond that. Flops: +, -, *, /, sqrt one each (a comparison, fabs, min,
max, floor: none); an FMA two. So the bound is optimistic: a kernel at 30 % of it may still be
at its real limit (a gather of scattered lines moves a 64 B line for 8 useful bytes, and a
dependent miss waits the latency, BM_Chase); what the table says is how much room the compulsory
traffic and arithmetic leave, kernel against kernel, and when one is at its limit.
The counts for hypre's PCG + PFMG are an estimate from its known structure (see pressure_solve;
the coarse operators' sizes are those of hypre's pfmg3_setup_rap.c: 7-point -> 19 -> 27).
One rank: per-rank counts are the report's totals / ranks.
"""
import argparse
import json
import math
import sys

# ---------------------------------------------------------------------------------------------
# the counts (bytes, flops per item), each with where it was counted


def T(count, nbytes, flops, what):
    """A term: `count` (a key of counts()) items, each nbytes and flops."""
    return {"count": count, "bytes": nbytes, "flops": flops, "what": what}


KERNELS = [
    {
        "name": "dem_pair_forces", "timer": "dem_force", "per": "substep",
        "unit": "touching pair", "primary": "touching", "isa": "avx512",
        "where": "dem/src/force_pass.hpp ForcePass::run, ScalarRows::row (forces_avx512.cpp "
                 "Avx512Rows::row with particles.force_isa=avx512), gatherPair, flush, "
                 "pairContact; dem/src/pairs.hpp pairChunk; dem/src/contact.hpp "
                 "pairForce<HertzMindlin, no rolling> (-march=native, -ffp-contract=off); the "
                 "list term counts every entry: with the pruned inner list a pass reads fewer",
        "terms": [
            T("particles", 192, 0,
              "Body 64 R (x, r, v, m packed), omega 24 R, f 24 R+W, torque 24 R+W, rowStart 4, "
              "binItems 4 (one material: no coefficient reads)"),
            T("list_entries", 8, 10,
              "nbr 4 R, slot 4 R; distance test: dx 3, r2 5, r_i + r_j and its square 2"),
            T("touching", 48, 140,
              "history 24 R + 24 W; R* m* 10, sqrt/1/r/n/delta 6, v_r and w_sum 12, pairForce "
              "Hertz 93 (stiffness 11, v_n F_n 8, tangential velocity 18, shear 17, F_t 3, "
              "Coulomb 9, cap/damp 12, F_p 6, n x F_t 9), scatter 18, tally 1"),
        ],
    },
    {
        "name": "dem_neighbour", "timer": "dem_neighbor", "per": "substep",
        "unit": "particle", "primary": "particles", "isa": "avx512",
        "where": "dem/src/neighbours.cpp maxDisplacement2 (every sub-step), buildLists, "
                 "keepPositions; dem/src/bins.cpp Bins::sort, sortByBin (at a rebuild)",
        "terms": [
            T("particles", 48, 8, "displacement check: x 24 R, x0 24 R; 3 sub, 3 mul, 2 add"),
            T("rebuild_particles", 916, 12,
              "sortByBin: x 24, bin 4 W + 4 R, items 4, ids 8; permutation of the 188 B row "
              "(id, material, x, v, omega, f, torque, f_ext, radius, mass) R+W 376 and its "
              "marks 352; buildLists: the same sort 44, x y z r 32 R, rowStart 4, history "
              "starts 8; keepPositions 48; binning 2 x 6 flops"),
            T("rebuild_candidates", 0, 11,
              "distance test of each candidate (13.5 bins x occupancy): dx 3, d2 5, cut 3"),
            T("rebuild_entries", 24, 0, "nbr 4 W, slot 4 W, history key 8 R + 8 W"),
        ],
    },
    {
        "name": "dem_integrate", "timer": "dem_integrate", "per": "substep",
        "unit": "particle", "primary": "particles", "isa": "avx512",
        "where": "dem/src/integrator.cpp initialIntegrate (with the sums' reset and the packed "
                 "Body), finalIntegrate",
        "terms": [
            T("particles", 504, 54,
              "initial: x v omega f torque f_ext 144 R, m r 16 R, x v omega f torque 120 W, "
              "Body 64 W; final: v omega f torque 96 R, m r 16 R, v omega 48 W; flops: half "
              "kicks 2 x 9 + 9, drift 6, inertia 2 x 3, reset 6, w 9"),
        ],
    },
    {
        "name": "fluid_momentum", "timer": "fluid_momentum", "per": "step",
        "unit": "cell", "primary": "cells", "isa": "avx512",
        "where": "fv/src/momentum.cpp massFluxes; fv/src/momentum_kernels.hpp kernel<VanLeer> "
                 "(explicitTerms) and predict (predictFaces, from step.cpp predictVelocity), "
                 "dispatched to the widest of SSE2 / AVX2 / AVX-512 the CPU runs",
        "terms": [
            T("cells", 480, 444,
              "mass fluxes 3 x (eps, u R, M W) 72 B 9 flops; explicit terms 3 x (u_d, M_d, "
              "2 u_e, 2 M_e, eps R, H W) 192 B, 3 x 125 flops (van Leer face values 6 each, "
              "12 a component along d and 2 x 46 across); update 3 x (eps, eps_old, K, KUp, "
              "H, H_old, u R; u_prev, u W) 216 B, 3 x 20 flops"),
        ],
    },
    {
        "name": "pressure_solve", "timer": "fluid_pressure_solve", "per": "step",
        "unit": "cell x PCG iteration", "primary": "cell_iterations", "isa": "sse2",
        "where": "hypre Struct PCG + PFMG V(1,1) preconditioner (fv/src/pressure_solver.cpp); "
                 "estimate from the structure, not from hypre's source",
        "terms": [
            T("cell_iterations", 1144, 217,
              "ESTIMATE: matvec 7-point 72 B 13 fl; PCG vectors (3 dots, 3 axpys) 112 B 12 fl; "
              "fine level of the V(1,1): 2 red-black sweeps 160 B 28 fl, residual 80 B 14 fl, "
              "restriction + interpolation 48 B 6 fl; coarse levels (semi-coarsening by 2: as "
              "many cells again, half on the first level with its 19-point Galerkin operator, "
              "half below with 27-point ones; per coarse cell of an s-point level 24 s + 120 B "
              "and 6 s + 6 fl) 672 B 144 fl; hypre's skipped relaxations not subtracted"),
        ],
        # the iterations re-read the same data: what the caches must hold is one copy of it
        "working_set": [("cells", 362, "fine 7-point matrix 56, coarse 19- and 27-point "
                                           "matrices 184, vectors x b r p s z and the coarse "
                                           "ones 122")],
    },
    {
        "name": "fluid_project", "timer": "fluid_project", "per": "step",
        "unit": "cell", "primary": "cells", "isa": "sse2",
        "where": "fv/src/step.cpp project, recordBalances",
        "terms": [
            T("cells", 208, 56,
              "p from the solution 16 B 2 fl; 3 faces x (eps, K, p, u R, u W) 120 B 33 fl; "
              "drag balance 3 x (KUp, K, u R) 72 B 21 fl"),
        ],
    },
    {
        "name": "coupling_sample", "timer": "coupling_interpolate", "per": "step",
        "unit": "particle", "primary": "particles", "isa": "sse2",
        "where": "coupling/src/kernel.cpp interpolateN<7> and <6>, pairs "
                 "(ParticleCoupling::evaluateDrag, sampleForForces), trilinear",
        "terms": [
            T("particles", 160, 233,
              "13 fields sampled in 2 passes: base 4 + 3 fractions 24 R a pass, 13 outputs "
              "W 104; weights 19 fl a pass, 15 fl a field"),
            T("cells", 104, 0, "the 13 fields R once a pass"),
        ],
    },
    {
        "name": "coupling_drag", "timer": "coupling_drag", "per": "step",
        "unit": "particle", "primary": "particles", "isa": "avx512_fma",
        "where": "coupling/src/particle_coupling.cpp evaluateDragOn, applyForces; "
                 "coupling/src/drag_packs.hpp dragPack<DiFelice> (SLEEF AVX-512); "
                 "coupling/src/simulation.cpp applyCouplingForces",
        "terms": [
            T("particles", 320, 208,
              "drag: u@p, v, eps@p, r, m, f, f_ext (held), V, grad p@p 152 R, beta, v~ 32 W; "
              "forces: beta, u@p, v~, V, grad p@p 112 R, f_ext 24 W; slip 9 fl, law ~138 fl "
              "(ESTIMATE: SLEEF log ~30, exp ~25), response 25, forces 33"),
            T("cells", 56, 12, "fluid's drag balance: K, u 3, KUp 3 R; 12 fl"),
        ],
    },
    {
        "name": "coupling_deposit", "timer": "coupling_deposit", "per": "step",
        "unit": "particle", "primary": "particles", "isa": "sse2",
        "where": "coupling/src/kernel.cpp Stencils::compute, depositN<5>; "
                 "coupling/src/particle_coupling.cpp locate, deposit; coupling/src/simulation.cpp "
                 "depositParticles, updateFluidCoefficients",
        "terms": [
            T("particles", 136, 119,
              "stencils: x 24 R, base 4, fractions 24, r 8 R, V 8 W (12 fl); deposit: V, beta, "
              "v~ 40 R, base + fractions 28 R; values 8 fl, weights 19, 5 x 4 pairs x 4 fl"),
            T("cells", 136, 2, "5 fields zeroed 40 W, deposited R+W 80, eps 16 (2 fl)"),
        ],
    },
]

ISA_PEAK = {  # bench_peak benchmark whose flops counter is the ceiling of an instruction set
    "scalar": "BM_MulAdd/0", "sse2": "BM_MulAdd/1", "avx2": "BM_MulAdd/2",
    "avx512": "BM_MulAdd/3", "avx2_fma": "BM_Fma/1", "avx512_fma": "BM_Fma/2",
}
# a CPU without an instruction set (bench_peak skips it) runs the -march=native DEM and SLEEF's
# dispatch on the next narrower one
ISA_FALLBACK = {"avx512": "avx2", "avx2": "sse2", "avx512_fma": "avx2_fma", "avx2_fma": "sse2"}


def isa_peak(pk, isa):
    """(instruction set, flop/s): `isa`, or the widest narrower one measured."""
    while isa not in pk and isa in ISA_FALLBACK:
        isa = ISA_FALLBACK[isa]
    return isa, pk[isa]

# ---------------------------------------------------------------------------------------------
# the counts of a run


def timed_steps(rep):
    run = rep["run"]
    return run["steps"] - run.get("first_step", 0)


def counts(rep, rebuild=None):
    """Items per pass of each kind, per rank (report totals / ranks), and the passes timed."""
    ranks = rep["mpi"]["ranks"]
    p = rep["particles"]
    n = p["count"] / ranks
    steps = timed_steps(rep)
    sub_per_step = rep["run"]["dem_substeps"] / rep["run"]["steps"]
    cells = math.prod(rep["config"]["domain"]["cells"]) / ranks
    rb = (rebuild or rep)["particles"]
    # rebuilds per sub-step of the loop (a fresh run: `rebuilds` counts those of the loop)
    src = rebuild or rep
    src_sub = timed_steps(src) * src["run"]["dem_substeps"] / src["run"]["steps"]
    per_sub = rb["rebuilds"] / max(src_sub, 1)
    bins = rb.get("bin_size", [1, 1, 1])
    length = rep["config"]["domain"]["length"]
    bed = rep.get("bed", {})
    vol = math.prod(length)
    if bed.get("bed_height_m"):
        axis = "xyz".index(bed.get("axis", "z"))
        vol = vol / length[axis] * bed["bed_height_m"]
    occupancy = p["count"] * math.prod(bins) / vol
    c = {
        "particles": n,
        "list_entries": p["neighbors_per_particle"] * n,
        "touching": p["contacts_per_particle"] * n / 2 + p.get("wall_contacts", 0) / ranks,
        "cells": cells,
        # + 1: the solve's start (residual and one preconditioning) costs about an iteration
        "cell_iterations": cells * (rep["pressure"]["iterations_avg"] + 1),
        "rebuild_particles": n * per_sub,
        "rebuild_candidates": n * per_sub * 13.5 * occupancy,
        "rebuild_entries": rb["neighbors_per_particle"] * n * per_sub,
    }
    # the timers cover the loop only (the set-up's list build and force pass are in `setup`)
    passes = {"step": steps, "substep": steps * sub_per_step}
    return c, passes, {"rebuilds_per_substep": per_sub, "bin_occupancy": occupancy}


# ---------------------------------------------------------------------------------------------
# the ceilings


def bench_rows(path):
    """{benchmark name: row} of a Google Benchmark JSON file."""
    with open(path) as f:
        data = json.load(f)
    return {b["name"]: b for b in data["benchmarks"] if not b.get("error_occurred")}, data


def bandwidth_curve(peak_rows, stream=None):
    """[(bytes of working set, bytes/s)] ascending: bench_stream's one-rank triad, else
    bench_peak's BM_Triad."""
    pts = []
    if stream:
        for mib, per_k in zip(stream["sizes_mib"], stream["per_rank_Bps"]):
            pts.append((mib * 1048576.0, per_k[0]))
    else:
        for name, r in peak_rows.items():
            if name.startswith("BM_Triad/"):
                pts.append((float(name.split("/")[1]) * 1048576.0, r["bytes"]))
    if not pts:
        raise SystemExit("roofline: no bandwidth (BM_Triad in --peak, or --stream)")
    return sorted(pts)


def bandwidth_at(curve, ws):
    """Triad bandwidth at working set ws (bytes): log-linear between measured sizes, clamped."""
    if ws <= curve[0][0]:
        return curve[0][1]
    for (s0, b0), (s1, b1) in zip(curve, curve[1:]):
        if ws <= s1:
            t = math.log(ws / s0) / math.log(s1 / s0)
            return b0 + t * (b1 - b0)
    return curve[-1][1]


def peaks(peak_rows):
    return {isa: peak_rows[b]["flops"] for isa, b in ISA_PEAK.items() if b in peak_rows}


# ---------------------------------------------------------------------------------------------
# the table


def table(rep, peak_rows, stream=None, rebuild=None):
    c, passes, derived = counts(rep, rebuild)
    curve = bandwidth_curve(peak_rows, stream)
    pk = peaks(peak_rows)
    rows = []
    for k in KERNELS:
        timer = rep["timers"].get(k["timer"])
        if timer is None:
            continue
        nbytes = sum(c[t["count"]] * t["bytes"] for t in k["terms"])
        flops = sum(c[t["count"]] * t["flops"] for t in k["terms"])
        units = c[k["primary"]]
        if units <= 0:
            continue
        busy = timer["busy_avg"] / passes[k["per"]]  # seconds a pass, one rank
        ws = sum(c[w[0]] * w[1] for w in k["working_set"]) if "working_set" in k else nbytes
        bw = bandwidth_at(curve, ws)
        isa, peak = isa_peak(pk, k["isa"])
        ai = flops / nbytes if nbytes > 0 else math.inf
        mem_rate = bw / (nbytes / units) if nbytes > 0 else math.inf
        flop_rate = peak / (flops / units) if flops > 0 else math.inf
        bound = min(mem_rate, flop_rate)
        achieved = units / busy if busy > 0 else math.inf
        rows.append({
            "kernel": k["name"], "timer": k["timer"], "unit": k["unit"], "isa": isa,
            "units_per_pass": units, "passes": passes[k["per"]], "per": k["per"],
            "bytes_per_unit": nbytes / units, "flops_per_unit": flops / units,
            "arithmetic_intensity": ai, "working_set_bytes": ws,
            "bandwidth_Bps": bw, "peak_flops": peak,
            "bound_units_per_s": bound, "achieved_units_per_s": achieved,
            "fraction_of_bound": achieved / bound, "binds": "memory" if mem_rate < flop_rate
            else "compute", "seconds_per_pass": busy, "where": k["where"],
            "terms": k["terms"],
        })
    ceilings = {"peak_flops": pk, "triad_Bps": [{"bytes": s, "Bps": b} for s, b in curve],
                "read_Bps": {n: r["bytes"] for n, r in peak_rows.items()
                             if n.startswith("BM_ReadSum/")},
                "latency_s": {n: r["seconds_per_load"] for n, r in peak_rows.items()
                              if n.startswith("BM_Chase/")}}
    return {"rows": rows, "counts": c, "derived": derived, "ceilings": ceilings}


def si(x, unit=""):
    for p, s in ((1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")):
        if abs(x) >= p:
            return f"{x / p:.3g} {s}{unit}"
    return f"{x:.3g} {unit}".rstrip()


def render(t, markdown):
    head = ["kernel", "unit", "units/pass", "B/unit", "flop/unit", "AI", "working set", "roof",
            "bound/s", "achieved/s", "fraction", "binds"]
    out = []
    for r in t["rows"]:
        roof = (f"{si(r['bandwidth_Bps'], 'B/s')}" if r["binds"] == "memory"
                else f"{si(r['peak_flops'], 'flop/s')}")
        out.append([r["kernel"], r["unit"], si(r["units_per_pass"]), f"{r['bytes_per_unit']:.0f}",
                    f"{r['flops_per_unit']:.0f}", f"{r['arithmetic_intensity']:.2f}",
                    f"{r['working_set_bytes'] / 1048576:.3g} MiB", roof,
                    si(r["bound_units_per_s"]), si(r["achieved_units_per_s"]),
                    f"{100 * r['fraction_of_bound']:.2g} %", r["binds"]])
    lines = []
    if markdown:
        lines.append("| " + " | ".join(head) + " |")
        lines.append("|" + "|".join("---" for _ in head) + "|")
        lines += ["| " + " | ".join(row) + " |" for row in out]
    else:
        w = [max(len(str(x[i])) for x in [head] + out) for i in range(len(head))]
        lines.append("  ".join(h.ljust(w[i]) for i, h in enumerate(head)))
        lines += ["  ".join(str(x).ljust(w[i]) for i, x in enumerate(row)) for row in out]
    ce = t["ceilings"]
    lines.append("")
    lines.append("peak (one core): " + ", ".join(f"{k} {si(v, 'flop/s')}"
                                                 for k, v in ce["peak_flops"].items()))
    lines.append("triad (one core): " + ", ".join(
        f"{p['bytes'] / 1048576:.3g} MiB {si(p['Bps'], 'B/s')}" for p in ce["triad_Bps"]))
    if ce["read_Bps"]:
        lines.append("read-only (one core): " + ", ".join(
            f"{n.split('/')[1]} MiB {si(v, 'B/s')}" for n, v in ce["read_Bps"].items()))
    if ce["latency_s"]:
        lines.append("dependent miss: " + ", ".join(
            f"{n.split('/')[1]} MiB {v * 1e9:.3g} ns" for n, v in ce["latency_s"].items()))
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--report", required=True, help="report.json of the run")
    ap.add_argument("--peak", required=True, help="bench_peak --benchmark_out JSON")
    ap.add_argument("--stream", help="bench_stream --json of a 1-rank run (else BM_Triad)")
    ap.add_argument("--rebuild-report",
                    help="report.json of the same run rebuilding every sub-step: dem_neighbour's "
                         "row from it (e.g. --set particles.skin=1e-6)")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--markdown", action="store_true")
    g.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    with open(a.report) as f:
        rep = json.load(f)
    peak_rows, _ = bench_rows(a.peak)
    stream = None
    if a.stream:
        with open(a.stream) as f:
            stream = json.load(f)
    rebuild = None
    if a.rebuild_report:
        with open(a.rebuild_report) as f:
            rebuild = json.load(f)
    t = table(rep, peak_rows, stream, rebuild)
    if rebuild:  # the neighbour row timed on the run that rebuilds
        tb = table(rebuild, peak_rows, stream, rebuild)
        t["rows"] = [next((r for r in tb["rows"] if r["kernel"] == "dem_neighbour"), r)
                     if r["kernel"] == "dem_neighbour" else r for r in t["rows"]]
    if a.json:
        json.dump(t, sys.stdout, indent=1)
        print()
    else:
        print(render(t, a.markdown))
    if rep["run"].get("first_step", 0):
        print("roofline: a restarted run: its rebuild count covers steps before the restart",
              file=sys.stderr)


if __name__ == "__main__":
    main()

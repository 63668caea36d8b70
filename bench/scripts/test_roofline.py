#!/usr/bin/env python3
"""Test of bench/scripts/roofline.py (CTest: roofline_unit, label unit).

A tiny fake report.json and bench_peak JSON whose numbers make the arithmetic checkable by hand:
the counts per pass, the bandwidth at a working set (log-linear between two measured sizes),
bytes and flops per unit, the bound as the lower ceiling, the achieved rate and its fraction, and
the --markdown and --json outputs. Prints "roofline: all checks passed" or the failures, exit 1.
"""
import contextlib
import io
import json
import math
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import roofline  # noqa: E402

FAILS = []
MIB = 1048576.0


def check(what, ok):
    if not ok:
        FAILS.append(what)


def close(a, b, rel=1e-9):
    return abs(a - b) <= rel * max(abs(a), abs(b))


def timer(busy, calls):
    return {"min": busy, "avg": busy, "max": busy, "calls": calls, "busy_avg": busy,
            "busy_max": busy}


def fake_report():
    names = ["dem_force", "dem_neighbor", "dem_integrate", "fluid_momentum",
             "fluid_pressure_solve", "fluid_project", "coupling_interpolate", "coupling_drag",
             "coupling_deposit"]
    timers = {n: timer(0.02, 20) for n in names}
    return {
        "config": {"domain": {"cells": [10, 10, 10], "length": [1.0, 1.0, 2.0]}},
        "mpi": {"ranks": 1},
        "run": {"steps": 2, "dem_substeps": 20},
        "particles": {"count": 1000, "contacts_per_particle": 4.0, "wall_contacts": 10,
                      "neighbors_per_particle": 6.0, "rebuilds": 2,
                      "bin_size": [0.1, 0.1, 0.1]},
        "bed": {"axis": "z", "bed_height_m": 1.0},
        "pressure": {"iterations_avg": 4.0},
        "timers": timers,
    }


def fake_peak():
    rows = [{"name": "BM_MulAdd/1", "flops": 10e9}, {"name": "BM_MulAdd/3", "flops": 100e9},
            {"name": "BM_Fma/2", "flops": 200e9},
            {"name": "BM_Triad/1", "bytes": 100e9}, {"name": "BM_Triad/256", "bytes": 10e9},
            {"name": "BM_ReadSum/256", "bytes": 12e9},
            {"name": "BM_Chase/256", "seconds_per_load": 100e-9},
            {"name": "BM_MulAdd/2", "error_occurred": True}]
    return {"context": {}, "benchmarks": rows}


def run():
    rep = fake_report()
    rows = {r["name"]: r for r in fake_peak()["benchmarks"] if not r.get("error_occurred")}
    # counts
    c, passes, derived = roofline.counts(rep)
    check("particles", c["particles"] == 1000)
    check("touching = contacts/2 + walls", c["touching"] == 2010)
    check("list entries", c["list_entries"] == 6000)
    check("cells", c["cells"] == 1000)
    check("cell iterations = cells x (its + 1)", c["cell_iterations"] == 5000)
    check("passes", passes == {"step": 2, "substep": 20})
    # 2 rebuilds over 20 sub-steps
    check("rebuilds per sub-step", close(derived["rebuilds_per_substep"], 0.1))
    # occupancy: 1000 particles x 1e-3 m^3 a bin / (1 x 1 x 1 m of bed)
    check("bin occupancy", close(derived["bin_occupancy"], 1.0))
    check("candidates", close(c["rebuild_candidates"], 1000 * 0.1 * 13.5))
    # bandwidth: log-linear between 1 MiB (100 GB/s) and 256 MiB (10 GB/s); clamped outside
    curve = roofline.bandwidth_curve(rows)
    check("curve", curve == [(MIB, 100e9), (256 * MIB, 10e9)])
    check("bw at 16 MiB", close(roofline.bandwidth_at(curve, 16 * MIB), 55e9))
    check("bw below", roofline.bandwidth_at(curve, 1.0) == 100e9)
    check("bw above", roofline.bandwidth_at(curve, 1e12) == 10e9)
    stream = {"sizes_mib": [3.0, 48.0], "per_rank_Bps": [[30e9, 20e9], [8e9, 5e9]]}
    check("stream curve: one rank", roofline.bandwidth_curve(rows, stream) ==
          [(3 * MIB, 30e9), (48 * MIB, 8e9)])
    # the table: dem_integrate by hand. 1000 particles, 504 B and 54 flops each; working set
    # 504,000 B < 1 MiB: 100 GB/s; memory 100e9 / 504 = 1.984e8 /s, compute 100e9 / 54 = 1.85e9
    # /s: memory binds; 0.02 s / 20 sub-steps = 1 ms a pass: 1e6 particles/s.
    t = roofline.table(rep, rows)
    r = {x["kernel"]: x for x in t["rows"]}
    check("every kernel", len(r) == len(roofline.KERNELS))
    i = r["dem_integrate"]
    check("integrate bytes/unit", close(i["bytes_per_unit"], 504))
    check("integrate AI", close(i["arithmetic_intensity"], 54 / 504))
    check("integrate bound", close(i["bound_units_per_s"], 100e9 / 504))
    check("integrate achieved", close(i["achieved_units_per_s"], 1e6))
    check("integrate fraction", close(i["fraction_of_bound"], 1e6 / (100e9 / 504)))
    check("integrate binds memory", i["binds"] == "memory")
    # pair forces: per touching pair (2010): (1000 x 192 + 6000 x 8 + 2010 x 48) B and
    # (6000 x 10 + 2010 x 140) flops; 0.02 s over 20 sub-steps: 1 ms a pass
    p = r["dem_pair_forces"]
    nb = 1000 * 192 + 6000 * 8 + 2010 * 48
    nf = 6000 * 10 + 2010 * 140
    check("pairs bytes/unit", close(p["bytes_per_unit"], nb / 2010))
    check("pairs flops/unit", close(p["flops_per_unit"], nf / 2010))
    check("pairs achieved", close(p["achieved_units_per_s"], 2010 / 1e-3))
    mem, comp = 100e9 / (nb / 2010), 100e9 / (nf / 2010)
    check("pairs bound", close(p["bound_units_per_s"], min(mem, comp)))
    check("pairs binds", p["binds"] == ("memory" if mem < comp else "compute"))
    # the pressure solve's working set: one copy of its data (362 B a cell), not the bytes of
    # every iteration: 362,000 B < 1 MiB: 100 GB/s
    ps = r["pressure_solve"]
    check("pressure working set", close(ps["working_set_bytes"], 362e3))
    check("pressure bandwidth", ps["bandwidth_Bps"] == 100e9)
    # the drag law's ceiling is AVX-512 FMA; the fluid's SSE2, but the momentum kernels' AVX-512
    # (run-time dispatch, no FMA)
    check("drag peak", r["coupling_drag"]["peak_flops"] == 200e9)
    # deposit: 2 steps, 0.02 s: 1000 particles / 0.01 s
    check("deposit achieved", close(r["coupling_deposit"]["achieved_units_per_s"], 1e5))
    check("momentum peak", r["fluid_momentum"]["peak_flops"] == 100e9)
    check("projection peak", r["fluid_project"]["peak_flops"] == 10e9)
    # a CPU without AVX-512: the DEM's ceiling falls back to AVX2 (here: BM_MulAdd/2 measured)
    no512 = {n: x for n, x in rows.items() if n not in ("BM_MulAdd/3", "BM_Fma/2")}
    no512["BM_MulAdd/2"] = {"name": "BM_MulAdd/2", "flops": 50e9}
    f = {x["kernel"]: x for x in roofline.table(rep, no512)["rows"]}
    check("fallback avx2", f["dem_integrate"]["isa"] == "avx2"
          and f["dem_integrate"]["peak_flops"] == 50e9)
    check("fallback fma -> sse2", f["coupling_drag"]["isa"] == "sse2")
    check("fallback momentum avx2", f["fluid_momentum"]["isa"] == "avx2"
          and f["fluid_momentum"]["peak_flops"] == 50e9)
    # a compute-bound case: a peak far below the bandwidth's rate
    slow = dict(rows, **{"BM_MulAdd/3": {"name": "BM_MulAdd/3", "flops": 1e6}})
    m = {x["kernel"]: x for x in roofline.table(rep, slow)["rows"]}["fluid_momentum"]
    check("compute binds", m["binds"] == "compute" and close(m["bound_units_per_s"], 1e6 / 444))
    # outputs
    with tempfile.TemporaryDirectory() as d:
        rp, pp = os.path.join(d, "report.json"), os.path.join(d, "peak.json")
        json.dump(rep, open(rp, "w"))
        json.dump(fake_peak(), open(pp, "w"))
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            roofline.main(["--report", rp, "--peak", pp, "--markdown"])
        md = out.getvalue()
        check("markdown header", md.startswith("| kernel | unit |"))
        check("markdown rows", md.count("\n| ") == len(roofline.KERNELS))
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            roofline.main(["--report", rp, "--peak", pp, "--json"])
        j = json.loads(out.getvalue())
        check("json rows", len(j["rows"]) == len(roofline.KERNELS))
        check("json latency", close(j["ceilings"]["latency_s"]["BM_Chase/256"], 100e-9))
        check("json finite", all(math.isfinite(x["fraction_of_bound"]) for x in j["rows"]))
    if FAILS:
        print("roofline: FAILED: " + "; ".join(FAILS))
        return 1
    print("roofline: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(run())

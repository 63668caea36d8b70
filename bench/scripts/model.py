#!/usr/bin/env python3
"""A calibrated performance MODEL of coloc's coupled step at rank counts that are not run.

time per step of rank r = unit costs measured on 1 rank (report.json timers)
                          x the rank's work from `coloc plan` (plan.json)
                        + its messages through a latency-bandwidth network model.

Unit costs (seconds, wall, from a 1-rank run of the same physics; fitted per case):
  fluid   per cell-step, excluding the pressure solve, plus per cell and pressure iteration;
  DEM     per particle and sub-step (neighbour, force, integrate; contacts folded in: the
          calibration runs start from rest, a per-contact cost cannot be told apart);
  coupling per particle-step (deposit, interpolate, drag) on the rank's coupled particles
          (its own particles co-located, the proxies it receives in the independent strategy).
Network per rank and step, per traffic kind of plan.json (bytes, messages):
  t = messages * latency + bytes / bandwidth_per_rank,
  bandwidth_per_rank = link bandwidth / ranks sharing a node's injection (min(ranks, per_node));
  the pressure solve adds per iteration 2 allreduces (latency x log2 P) and a one-layer halo of p
  on each of ~2 multigrid levels' worth of cells (6 messages a level).
Shares: fluid = fluid work + fluid halos + pressure messages; DEM = DEM work + ghost updates;
coupling = coupling arithmetic; inter-physics = deposit sum + proxies (+ the in-rank copies of
the independent strategy at memory speed); wait = step - mean rank time (imbalance). The step is
the slowest rank's time (the two timed barriers of a step make every rank wait for it).

Usage:
  model.py calibrate REPORT_1RANK.json > costs.json
  model.py predict --costs costs.json --plan plan.json --profile edr-ib|PINGPONG.json
                   [--csv out.csv] [--png out.png] [--title T]
"""
import argparse
import json
import math
import sys

FLUID = ["fluid_momentum", "fluid_boundary", "fluid_pressure_assemble", "fluid_project",
         "fluid_cell_fields"]
DEM = ["dem_neighbor", "dem_force", "dem_integrate"]
COUPLING = ["coupling_deposit", "coupling_interpolate", "coupling_drag"]
PROFILES = {
    # EDR InfiniBand: ~1 us, ~12 GB/s per link, 28 ranks a node sharing the injection bandwidth.
    "edr-ib": {"latency_s": 1.0e-6, "bandwidth_Bps": 12.0e9, "ranks_per_node": 28,
               "memory_Bps": 10.0e9},
}


KEY = "avg"


def t(report, name):
    return report["timers"].get(name, {}).get(KEY, 0.0)


def calibrate(report):
    steps = report["run"]["steps"] - report["run"].get("first_step", 0)
    sub = report["run"]["dem_substeps"]
    cells = 1
    for c in report["config"]["domain"]["cells"]:
        cells *= c
    n = report["particles"]["count"] if "particles" in report else 0
    iters = report.get("pressure", {}).get("iterations_avg", 0.0) * steps
    solve = t(report, "fluid_pressure_solve")
    fluid = sum(t(report, p) for p in FLUID)
    dem = sum(t(report, p) for p in DEM)
    cpl = sum(t(report, p) for p in COUPLING)
    frozen = report.get("particles", {}).get("frozen", False)
    return {
        "source": report["case"] if isinstance(report["case"], str) else str(report["case"]),
        "fluid_per_cell_step": fluid / (cells * steps),
        "pressure_per_cell_iteration": solve / (cells * iters) if iters > 0 else 0.0,
        "pressure_iterations_per_step": iters / steps,
        "dem_per_particle_substep": 0.0 if frozen or sub == 0 or n == 0 else dem / (n * sub),
        "coupling_per_particle_step": cpl / (n * steps) if n else 0.0,
        "timer": "wall" if KEY == "avg" else "busy (thread CPU)",
        "measured_step_s": report["run"]["wall_s"] / steps,
        "measured_busy_step_s": report["load"]["busy_s_max"] / steps,
        "measured_fractions": report["fractions"],
    }


def profile(spec):
    if spec in PROFILES:
        return dict(PROFILES[spec], name=spec)
    with open(spec) as f:
        p = json.load(f)
    # this machine: the measured ping-pong, both ranks on one node (shared memory)
    return {"latency_s": p["latency_s"], "bandwidth_Bps": p["bandwidth_Bps"],
            "ranks_per_node": 1, "memory_Bps": p["bandwidth_Bps"], "name": "this machine"}


def predict_layout(costs, layout, prof):
    P = layout["ranks"]
    pr = layout["per_rank"]
    ks = pr["per_step"]
    sub = layout["dem_substeps_per_step"]
    indep = layout["strategy"] == "independent"
    share = min(P, prof["ranks_per_node"]) if prof["ranks_per_node"] > 1 else 1
    bw = prof["bandwidth_Bps"] / share
    lat = prof["latency_s"]
    iters = costs["pressure_iterations_per_step"]
    logp = math.ceil(math.log2(P)) if P > 1 else 0

    def net(kind, r):
        return ks[kind]["messages"][r] * lat + ks[kind]["bytes"][r] / bw

    rows = []
    for r in range(P):
        cells, parts = pr["cells"][r], pr["particles"][r]
        coupled = pr["proxies"][r] if indep else parts
        fluid = cells * (costs["fluid_per_cell_step"] + iters * costs["pressure_per_cell_iteration"])
        halo_p = pr["ghost_cells"][r] / 2 * 8  # one layer of p
        pressure_net = iters * (2 * lat * logp + (2 * (6 * lat if P > 1 else 0) +
                                                  2 * halo_p / bw))
        fluid_net = net("fluid_halo", r) + net("coupling_halo", r) + pressure_net
        dem = parts * sub * costs["dem_per_particle_substep"]
        dem_net = net("dem_ghost", r)
        cpl = coupled * costs["coupling_per_particle_step"]
        inter = net("deposit_sum", r) + net("proxy", r)
        if indep:
            inter += ks["force_handover"]["bytes"][r] / prof["memory_Bps"]
        rows.append((fluid + fluid_net, dem + dem_net, cpl, inter))
    tot = [sum(x) for x in rows]
    step = max(tot)
    mean = [sum(x[i] for x in rows) / P for i in range(4)]
    busy = sum(mean)
    return {"strategy": layout["strategy"], "ranks": P, "step_s": step,
            "fluid": mean[0] / step, "dem": mean[1] / step, "coupling": mean[2] / step,
            "inter_physics": mean[3] / step, "wait": 1 - busy / step,
            "imbalance": step / busy if busy > 0 else 1.0,
            "fluid_of_busy": mean[0] / busy, "dem_of_busy": mean[1] / busy,
            "coupling_of_busy": mean[2] / busy, "inter_physics_of_busy": mean[3] / busy}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    sp = ap.add_subparsers(dest="cmd", required=True)
    c = sp.add_parser("calibrate")
    c.add_argument("report")
    c.add_argument("--busy", action="store_true",
                   help="fit thread-CPU (busy) times instead of wall: on a shared, loaded machine")
    p = sp.add_parser("predict")
    p.add_argument("--costs", required=True)
    p.add_argument("--plan", required=True)
    p.add_argument("--profile", required=True)
    p.add_argument("--csv")
    p.add_argument("--png")
    p.add_argument("--title", default="")
    a = ap.parse_args()
    if a.cmd == "calibrate":
        global KEY
        if a.busy:
            KEY = "busy_avg"
        with open(a.report) as f:
            json.dump(calibrate(json.load(f)), sys.stdout, indent=1)
        print()
        return
    with open(a.costs) as f:
        costs = json.load(f)
    with open(a.plan) as f:
        plan = json.load(f)
    prof = profile(a.profile)
    out = [predict_layout(costs, L, prof) for L in plan["layouts"] if "error" not in L]
    base = {}
    for r in out:
        if r["ranks"] == 1 or r["strategy"] not in base or r["ranks"] < base[r["strategy"]][0]:
            base.setdefault(r["strategy"], (r["ranks"], r["step_s"] * r["ranks"]))
    # speedup against one rank's modelled time (the serial work: sum of the work of all ranks)
    serial = None
    for r in out:
        if r["ranks"] == 1:
            serial = r["step_s"]
    keys = ["strategy", "ranks", "step_s", "speedup", "fluid", "dem", "coupling", "inter_physics",
            "wait", "imbalance", "fluid_of_busy", "dem_of_busy", "coupling_of_busy",
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
        fig.suptitle("MODEL (not measured): %s, profile %s, unit costs from %s" %
                     (a.title or plan["case"], prof["name"], costs["source"]))
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()

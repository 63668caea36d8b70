#!/usr/bin/python3
"""Alternating rounds of the settled-bed DEM comparison (docs/benchmarks.md, "DEM bed").

Each round runs every code once, back to back, pinned to one core (taskset -c CORE), and prints
million particle-steps per second by wall time and by CPU time, with the load average at the
round's start. Codes (any subset, in the order given):

  lammps:PATH_TO_DATA           LAMMPS gran/hertz/history (lmp), bench/peers/dem-bed.lammps
  liggghts:PATH_TO_DATA         LIGGGHTS (liggghts), bench/peers/dem-bed.liggghts
  coloc:LABEL:BINARY:STATE[:CASE]  bench_dem BM_DemBed restored from STATE (DEM_BED_LOAD)

  dem_bed_rounds.py --rounds 5 --nrelax 200 --nsteps 1000 \
      lammps:/tmp/bed.data coloc:main:/tmp/bench_dem_main:/tmp/bed.state \
      coloc:new:build/bench/bench_dem:/tmp/bed.state

Each round also prints every code's rate over the first code's (the peer when it comes first),
by wall and by CPU time; at the end, min / median / max over the rounds of each code's rates
and of those ratios. --csv FILE appends each run (UTC start, round, code, rates, load) to FILE
and takes the summary over every round in it: rounds run by separate invocations at different
times of a session end up in one summary (the same codes in the same order each time).
"""
import argparse
import csv
import os
import re
import statistics
import subprocess
import time


def run(cmd, env=None):
    t0 = time.time()
    r = subprocess.run(["/usr/bin/time", "-f", "TIME %e %U %S %M"] + cmd, capture_output=True,
                       text=True, env=env)
    out = r.stdout + r.stderr
    if r.returncode != 0:
        raise SystemExit("failed: %s\n%s" % (" ".join(cmd), out[-3000:]))
    return out, time.time() - t0


def peer(kind, data, a):
    peers = a.peers
    if kind == "lammps":
        cmd = ["taskset", "-c", a.core, "lmp", "-in", os.path.join(peers, "dem-bed.lammps"), "-var",
               "data", data, "-var", "nrelax", str(a.nrelax), "-var", "nsteps", str(a.nsteps),
               "-var", "model", "hertz", "-log", "none"]
    else:
        cmd = ["taskset", "-c", a.core, "liggghts", "-nocite", "-log", "none", "-in",
               os.path.join(peers, "dem-bed.liggghts"), "-var", "data", data, "-var", "zhi",
               str(a.zhi), "-var", "nrelax", str(a.nrelax), "-var", "nsteps", str(a.nsteps)]
    out, _ = run(cmd)
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on \d+ procs for (\d+) steps with (\d+) atoms",
                       out)
    loop, steps, atoms = float(loops[-2][0]), int(loops[-2][1]), int(loops[-2][2])
    cpu = re.findall(r"([0-9.]+)% CPU use", out)
    if len(cpu) >= 2:
        frac = float(cpu[-2]) / 100
    else:  # LIGGGHTS prints no "% CPU use": the whole process's CPU / wall (/usr/bin/time)
        t = re.search(r"TIME (\S+) (\S+) (\S+)", out)
        frac = (float(t.group(2)) + float(t.group(3))) / float(t.group(1))
    z = re.findall(r"coordination[^=]*= ([0-9.]+)", out)
    wall_rate = atoms * steps / loop / 1e6
    cpu_rate = wall_rate / frac if frac else None
    return wall_rate, cpu_rate, "Z=%s" % (z[-1] if z else "?")


def coloc(binary, state, case, a):
    env = dict(os.environ, DEM_BED_LOAD=state, DEM_BED_SETTLE="0")
    if case:
        env["DEM_BED_CASE"] = case
    out, _ = run(["taskset", "-c", a.core, binary, "--benchmark_filter=DemBed"], env=env)
    m = re.search(r"BM_DemBed\S*\s+([0-9.]+) ms\s+([0-9.]+) ms.*?particles=([0-9.]+)([kM]?)", out)
    wall, cpu = float(m.group(1)), float(m.group(2))
    n = float(m.group(3)) * {"": 1, "k": 1e3, "M": 1e6}[m.group(4)]
    z = re.search(r"contacts_per_particle=([0-9.]+)", out).group(1)
    b = re.search(r"bytes_per_particle=([0-9.]+)", out).group(1)
    rss = re.search(r"rss_run_per_particle=([0-9.]+)([k]?)", out)  # absent in older builds
    rssv = "%.0f" % (float(rss.group(1)) * (1e3 if rss.group(2) == "k" else 1)) if rss else "-"
    peak = re.search(r"TIME \S+ \S+ \S+ (\d+)", out).group(1)
    return (n * 100 / wall / 1e3, n * 100 / cpu / 1e3,
            "Z=%s B/particle=%s rss_run=%s peakRSS=%.0f MB" % (z, b, rssv, int(peak) / 1024))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--core", default="1")
    ap.add_argument("--peers", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                      "..", "peers"),
                    help="folder with dem-bed.lammps and dem-bed.liggghts (default bench/peers)")
    ap.add_argument("--nrelax", type=int, default=200)
    ap.add_argument("--nsteps", type=int, default=1000)
    ap.add_argument("--zhi", type=float, default=0.06)
    ap.add_argument("--csv", help="append the runs to this CSV; summary over all its rounds")
    ap.add_argument("codes", nargs="+")
    a = ap.parse_args()
    rows = []  # (round, label, wall, cpu)
    if a.csv and os.path.exists(a.csv):
        with open(a.csv, newline="") as f:
            rows = [(int(r["round"]), r["code"], float(r["wall_M"]),
                     float(r["cpu_M"]) if r["cpu_M"] else None) for r in csv.DictReader(f)]
    first = 1 + max((r[0] for r in rows), default=0)
    for r in range(first, first + a.rounds):
        load = open("/proc/loadavg").read().split()[:3]
        utc = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime())
        print("round %d  %s  load %s" % (r, utc[11:], " ".join(load)), flush=True)
        base = None
        for c in a.codes:
            f = c.split(":")
            if f[0] in ("lammps", "liggghts"):
                w, u, extra = peer(f[0], f[1], a)
                label = f[0]
            else:
                w, u, extra = coloc(f[2], f[3], f[4] if len(f) > 4 else None, a)
                label = "coloc " + f[1]
            base = base or (label, w, u)
            ratio = ""
            if label != base[0]:
                ratio = "  / %s: wall %.2fx cpu %s" % (
                    base[0], w / base[1], "%.2fx" % (u / base[2]) if u and base[2] else "n/a")
            print("  %-14s wall %6.2f M  cpu %s  %s%s" % (
                label, w, "%6.2f M" % u if u else "   n/a", extra, ratio), flush=True)
            rows.append((r, label, w, u))
            if a.csv:
                new = not os.path.exists(a.csv)
                with open(a.csv, "a", newline="") as f:
                    wr = csv.writer(f)
                    if new:
                        wr.writerow(["utc", "round", "code", "wall_M", "cpu_M", "load1", "extra"])
                    wr.writerow([utc, r, label, "%.4f" % w, "%.4f" % u if u else "", load[0],
                                 extra])
    summary(rows)


def summary(rows):
    """min / median / max over the rounds of each code's rates and of its ratio to the first
    code of its round (million particle-steps/s; ratio above 1: faster than that code)."""
    def mmm(v):
        return "%.2f / %.2f / %.2f" % (min(v), statistics.median(v), max(v)) if v else "n/a"
    rounds = {}
    for r, label, w, u in rows:
        rounds.setdefault(r, []).append((label, w, u))
    labels = []
    for _, label, _, _ in rows:
        labels += [label] if label not in labels else []
    print("summary over %d rounds, min / median / max (M particle-steps/s; ratio to the "
          "round's first code):" % len(rounds))
    for lab in labels:
        w = [x[1] for rr in rounds.values() for x in rr if x[0] == lab]
        u = [x[2] for rr in rounds.values() for x in rr if x[0] == lab and x[2]]
        rw = [x[1] / rr[0][1] for rr in rounds.values() for x in rr
              if x[0] == lab and rr[0][0] != lab]
        ru = [x[2] / rr[0][2] for rr in rounds.values() for x in rr
              if x[0] == lab and rr[0][0] != lab and x[2] and rr[0][2]]
        line = "  %-14s wall %s  cpu %s" % (lab, mmm(w), mmm(u))
        if rw:
            line += "  ratio wall %s  cpu %s" % (mmm(rw), mmm(ru))
        print(line, flush=True)


if __name__ == "__main__":
    main()

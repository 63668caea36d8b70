#!/usr/bin/env python3
"""Run coloc's SimGrid SMPI build on a simulated cluster (docs/smpi.md).

    bench/scripts/smpi_run.py --ranks 64 [--platform paper] [--smpi-build build-smpi] \
        -- run bench/cases/case3-small.json --set run.steps=3 --out OUT

Writes the hostfile of the platform (one line per rank, ranks filled node by node as
`mpirun --map-by core` does), calls smpirun with the settings coloc's simulations use (below,
one place), and prints the wall time and peak memory of the simulation after coloc's own output.
coloc's report.json then holds *simulated* seconds (MPI_Wtime is the simulated clock).

The settings, and why:
  smpi/host-speed:1Gf  the platforms' cores are 1 Gflop/s: a compute burst costs on the
                       simulated core exactly what it took on this machine's core.
  smpi/bw-factor, smpi/lat-factor 0:1   no piece-wise correction of bandwidth and latency: SMPI's
                       defaults are fitted to another cluster; the platform file says it all.
  smpi/iprobe, smpi/test   the simulated cost of one MPI_Iprobe / MPI_Test that finds nothing:
                       what one costs a real rank of the Open MPI build on this machine
                       (bench_mpi_calls, measured with the calibration below; 1e-7 s when the
                       real build is not there). SMPI's defaults (1e-4 s and more) charge
                       hypre's set-up, which polls with MPI_Iprobe while it exchanges its
                       assumed partition, seconds of simulated time per step.
  smpi/grow-injected-times:no   SMPI's default multiplies those costs after each poll that finds
                       nothing, with one multiplier shared by every simulated rank (SimGrid 3.32,
                       Request::iprobe): one rank's failed polls raised every rank's charge, and
                       the result depended on the order the simulator ran them.
  smpi/send-is-detached-thresh 0   no send is detached (SMPI's default detaches sends under 64 KiB,
                       as an eager protocol would): SimGrid 3.32 keeps every detached send of the
                       whole simulation in one list and scans it each time one completes, which
                       costs O((messages in flight)^2), i.e. O(P^2) per exchange: at 1024 ranks
                       case3-small's set-up did not finish in 29 minutes. A send that is not
                       detached completes when its receive has matched (the receives of coloc's and
                       hypre's exchanges are posted first, so that is at once), in the sending
                       rank's own short list (SimGrid 3.34 replaced the lists by sets).
  smpi/coll-selector ompi   the collective algorithms of a real MPI library (Open MPI's choices
                       by message and communicator size); --coll overrides. The paper's runs used
                       Intel MPI 5.1, but SMPI's impi selector crashes (segmentation fault) in
                       the balanced strategy's set-up at 64 ranks, and its mpich selector aborts
                       (mismatched datatypes). SMPI's own default is a naive set (its source says
                       it is not to be trusted for performance): MPI_Allreduce is a linear reduce to rank 0 then
                       a broadcast, MPI_Allgather P-1 sends a rank, MPI_Barrier linear. That
                       charges the root P-1 serialised messages per reduction and costs the
                       simulator O(P^2) per collective (the root's wait for P-1 requests is P-1
                       waitany calls): 1024 ranks did not finish their set-up in 29 minutes.

And one correction of what SMPI charges (--burst-charge, docs/smpi.md "What SMPI charges a
rank"): SMPI times each burst of a rank with the thread's CPU clock, and the interval it times
holds its own code at the ends of the two MPI calls and one read of that clock (a system call:
~1.3 us here). An empty burst is charged ~2 us at 2 ranks and more at hundreds (the simulator's
own state for the other ranks evicts the caches), which a real rank does not spend, on each of
the thousands of MPI calls hypre makes a step. By default (measured) this script first
calibrates, on this machine now:
  - the charge of an empty burst at the run's rank count: smpi_empty_bursts (the ranks only pass
    a double around a ring) under the simulator, the median burst;
  - what one MPI call costs a real rank: bench_mpi_calls of the Open MPI build (--real-build,
    default build/) on 2 real ranks: one MPI_Iprobe, one MPI_Test;
then preloads libcoloc_smpi_burst.so, which subtracts from every burst of the run (never below
0) the empty burst's charge less the real call's cost (the real rank spends that much in its
MPI call; SMPI charges the call itself nothing but the network). The calibration is printed and
written into the run's report.json (provenance.smpi_calibration). --burst-charge none leaves
SMPI's charge as it is; --burst-charge SECONDS subtracts a given charge; --calibration FILE
reads a calibration written before (--save-calibration FILE) instead of measuring.

And the simulated ranks' heap: they share one process, so one glibc heap. A real rank's heap is
its own, and once warm (glibc raises its mmap threshold to the largest block freed, up to
32 MiB, and its trim threshold to twice that) it reuses its pages step after step; in the
shared heap, the blocks hypre's set-up frees are trimmed or unmapped and the next rank's
allocations fault them in again, and the kernel's zeroing of those pages is timed as that rank's
computation. MALLOC_MMAP_THRESHOLD_=32 MiB and MALLOC_TRIM_THRESHOLD_=64 GiB (unless set in the
environment) give the simulation a warm real rank's heap: at 112 ranks of case 2 they halved the
simulated pressure set-up (docs/smpi.md, "The charge of an empty burst").
"""
import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PLATFORMS = os.path.join(ROOT, "bench", "platforms")
SETTINGS = ["--cfg=smpi/host-speed:1Gf", "--cfg=smpi/bw-factor:0:1", "--cfg=smpi/lat-factor:0:1",
            "--cfg=smpi/send-is-detached-thresh:0", "--cfg=smpi/grow-injected-times:no"]
POLL_DEFAULT_S = 1e-7  # smpi/iprobe and smpi/test without a measurement of the real build


def platform_file(name):
    path = name if name.endswith(".xml") else os.path.join(PLATFORMS, name + "-cluster.xml")
    if not os.path.isfile(path):
        sys.exit(f"smpi_run.py: no platform file '{path}' (bench/platforms/*-cluster.xml)")
    return path


def cluster_attributes(path):
    """The attributes of the platform's <cluster> element, as strings."""
    text = open(path).read()
    m = re.search(r"<cluster\b[^>]*>", text)
    if not m:
        sys.exit(f"smpi_run.py: {path} has no <cluster> element")
    return dict(re.findall(r'(\w+)="([^"]*)"', m.group(0)))


def cluster_shape(path):
    """(prefix, first node, last node, cores a node) of the platform's <cluster>."""
    attrs = cluster_attributes(path)
    lo, hi = (int(v) for v in attrs["radical"].split("-"))
    return attrs.get("prefix", ""), lo, hi, int(attrs.get("core", "1")), attrs.get("suffix", "")


def write_hostfile(path, platform, ranks):
    prefix, lo, hi, cores, suffix = cluster_shape(platform)
    if ranks > (hi - lo + 1) * cores:
        sys.exit(f"smpi_run.py: {ranks} ranks do not fit on {platform} "
                 f"({hi - lo + 1} nodes of {cores} cores)")
    with open(path, "w") as f:
        for r in range(ranks):
            f.write(f"{prefix}{lo + r // cores}{suffix}\n")


def smpirun_command(ranks, platform, tmp, coll, cfgs, exe, args, poll=None):
    hosts = os.path.join(tmp, f"hosts-{ranks}.txt")
    write_hostfile(hosts, platform, ranks)
    poll = poll or {}
    polls = [f"--cfg=smpi/iprobe:{poll.get('iprobe_s', POLL_DEFAULT_S):.3e}",
             f"--cfg=smpi/test:{poll.get('test_s', POLL_DEFAULT_S):.3e}"]
    return (["smpirun", "-np", str(ranks), "-platform", platform, "-hostfile", hosts,
             "--cfg=smpi/tmpdir:" + tmp, "--log=root.thres:warning"] + SETTINGS + polls +
            ["--cfg=smpi/coll-selector:" + coll] + ["--cfg=" + c for c in cfgs] + [exe] + args)


def burst_library(smpi_build):
    """The preloaded library and the probe of bench/smpi (built with the SMPI build)."""
    lib = os.path.join(smpi_build, "libcoloc_smpi_burst.so")
    probe = os.path.join(smpi_build, "smpi_empty_bursts")
    for f in (lib, probe):
        if not os.path.isfile(f):
            sys.exit(f"smpi_run.py: no '{f}': build it with cmake/setup-smpi.sh "
                     "(or run with --burst-charge none)")
    return lib, probe


HEAP = {"MALLOC_MMAP_THRESHOLD_": str(32 << 20), "MALLOC_TRIM_THRESHOLD_": str(64 << 30)}


def simulation_env():
    """The environment of smpirun: a warm real rank's heap for the ranks' shared one."""
    return {**HEAP, **os.environ}


def preload_env(lib, offset, stats=None):
    env = simulation_env()
    env["LD_PRELOAD"] = lib + (" " + env["LD_PRELOAD"] if env.get("LD_PRELOAD") else "")
    env["COLOC_SMPI_BURST_OFFSET"] = repr(offset)
    if stats:
        env["COLOC_SMPI_BURST_STATS"] = stats
    else:
        env.pop("COLOC_SMPI_BURST_STATS", None)
    return env


def measure_empty_burst(lib, probe, platform, tmp, coll, cfgs, ranks=2, iters=None):
    """The median charge SMPI gives an empty burst at `ranks` simulated ranks on this machine
    now (seconds): ~40,000 bursts in all (at least 50 exchanges a rank)."""
    stats = os.path.join(tmp, "empty_bursts.json")
    ranks = max(2, ranks)
    iters = iters or max(50, 40000 // ranks)
    cmd = smpirun_command(ranks, platform, tmp, coll, cfgs, probe, [str(iters)])
    out = subprocess.run(cmd, env=preload_env(lib, 0.0, stats), capture_output=True, text=True)
    if out.returncode != 0 or not os.path.isfile(stats):
        sys.stderr.write(out.stdout + out.stderr)
        sys.exit(f"smpi_run.py: measuring the charge of an empty burst failed (exit {out.returncode})")
    with open(stats) as f:
        st = json.load(f)
    return st["median_s"], st


def measure_real_calls(real_build):
    """What one MPI_Iprobe and one MPI_Test cost a real rank of the Open MPI build here (2 ranks,
    bench_mpi_calls), or None (and why) without that build or mpirun."""
    exe = os.path.join(real_build, "bench", "bench_mpi_calls")
    mpirun = shutil.which("mpirun")
    if not os.path.isfile(exe) or not mpirun:
        return None, f"no {exe}" if mpirun else "no mpirun"
    # a real rank as a timed run has it: polling, not yielding its core (with yield each call
    # costs ~0.7 us here instead of ~0.08), whatever the caller's environment says
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_mpi_yield_when_idle": "0"}
    out = subprocess.run([mpirun, "-n", "2", "--bind-to", "none", exe, "100000", "9"],
                         capture_output=True, text=True, env=env)
    try:
        return json.loads(out.stdout.strip().splitlines()[-1]), None
    except (ValueError, IndexError):
        return None, f"bench_mpi_calls failed (exit {out.returncode}): {out.stderr.strip()[-200:]}"


def calibrate(a, lib, probe, platform, tmp):
    """The calibration of this run (module docstring): a dict of seconds and where they came
    from; its `offset_s` is subtracted from every burst."""
    if a.calibration:
        try:
            with open(a.calibration) as f:
                cal = json.load(f)
            float(cal["offset_s"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            sys.exit(f"smpi_run.py: --calibration '{a.calibration}': {e}")
        cal["source"] = os.path.abspath(a.calibration)
        return cal
    cal = {"ranks": a.ranks, "iprobe_s": POLL_DEFAULT_S, "test_s": POLL_DEFAULT_S}
    real, why = measure_real_calls(a.real_build)
    if real:
        cal.update(iprobe_s=real["iprobe_s"], test_s=real["test_s"],
                   real_exchange_s=real["exchange_s"], real_call_s=real["iprobe_s"])
    else:
        cal.update(real_call_s=0.0, real_calls_missing=why)
    if a.burst_charge == "measured":
        med, st = measure_empty_burst(lib, probe, platform, tmp, a.coll, a.cfg, a.ranks)
        cal.update(empty_burst_s=med, empty_burst_p10_s=st["p10_s"],
                   empty_burst_p90_s=st["p90_s"], empty_bursts=st["bursts"])
        cal["offset_s"] = max(0.0, med - cal["real_call_s"])
    elif a.burst_charge == "none":
        cal["offset_s"] = 0.0
    else:
        cal["offset_s"] = a.burst_charge
    cal["source"] = "measured by smpi_run.py " + time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return cal


def stamp_report(args, cal):
    """The calibration into the run's report.json (provenance.smpi_calibration), if it wrote one."""
    out = None
    for i, x in enumerate(args):
        if x == "--out" and i + 1 < len(args):
            out = args[i + 1]
        elif x.startswith("--out="):
            out = x.split("=", 1)[1]
    path = os.path.join(out, "report.json") if out else None
    if not path or not os.path.isfile(path):
        return
    with open(path) as f:
        rep = json.load(f)
    rep.setdefault("provenance", {})["smpi_calibration"] = cal
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(rep, f, indent=2)
    os.replace(tmp, path)


def burst_charge(value):
    if value in ("measured", "none"):
        return value
    try:
        v = float(value)
    except ValueError:
        v = -1.0
    if not v >= 0:
        raise argparse.ArgumentTypeError(f"'{value}': measured, none, or seconds >= 0")
    return v


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ranks", type=int, required=True, help="simulated MPI ranks")
    ap.add_argument("--platform", default="paper", help="paper, current, or a SimGrid XML file")
    ap.add_argument("--smpi-build", default=os.path.join(ROOT, "build-smpi"),
                    help="the SMPI build folder (cmake/setup-smpi.sh)")
    ap.add_argument("--exe", help="another program of the SMPI build (e.g. a test) instead of coloc")
    ap.add_argument("--coll", default="ompi",
                    help="SMPI collective selector (ompi, impi, mpich, mvapich2, default); default: ompi")
    ap.add_argument("--cfg", action="append", default=[],
                    help="extra SimGrid setting, e.g. --cfg smpi/privatization:no")
    ap.add_argument("--burst-charge", type=burst_charge, default="measured",
                    help="what to subtract from each timed burst: measured (default: the median "
                    "charge of an empty burst, measured first), none (SMPI's charge), or seconds")
    ap.add_argument("--real-build", default=os.path.join(ROOT, "build"),
                    help="the Open MPI build whose bench_mpi_calls gives a real call's cost "
                    "(default: build/)")
    ap.add_argument("--calibration", help="read the calibration from this file (written by "
                    "--save-calibration) instead of measuring it")
    ap.add_argument("--save-calibration", help="write this run's calibration to this file")
    ap.add_argument("coloc_args", nargs=argparse.REMAINDER, help="-- then coloc's arguments")
    a = ap.parse_args()
    args = a.coloc_args[1:] if a.coloc_args[:1] == ["--"] else a.coloc_args
    exe = a.exe or os.path.join(a.smpi_build, "coloc")
    if not os.path.isfile(exe):
        sys.exit(f"smpi_run.py: no '{exe}': build it with cmake/setup-smpi.sh")
    if not shutil.which("smpirun"):
        sys.exit("smpi_run.py: smpirun not found (cmake/setup-smpi.sh installs SimGrid)")
    platform = platform_file(a.platform)
    with tempfile.TemporaryDirectory(prefix="coloc-smpi-") as tmp:
        env = simulation_env()
        lib, probe = burst_library(a.smpi_build) if a.burst_charge != "none" else (None, None)
        cal = calibrate(a, lib, probe, platform, tmp)
        offset = float(cal["offset_s"])
        if "empty_burst_s" in cal:
            print(f"smpi_run.py: an empty burst is charged {1e6 * cal['empty_burst_s']:.3f} us at "
                  f"{cal.get('ranks', '?')} simulated ranks (median of {cal.get('empty_bursts', '?')}; "
                  f"10th-90th percentile {1e6 * cal['empty_burst_p10_s']:.3f}-"
                  f"{1e6 * cal['empty_burst_p90_s']:.3f} us); a real call costs "
                  f"{1e6 * cal['real_call_s']:.3f} us: {1e6 * offset:.3f} us subtracted from every "
                  "burst", flush=True)
        if "real_calls_missing" in cal:
            print(f"smpi_run.py: the real call's cost is not measured ({cal['real_calls_missing']}): "
                  f"MPI_Iprobe and MPI_Test charged {POLL_DEFAULT_S:g} s", flush=True)
        if a.save_calibration:
            with open(a.save_calibration, "w") as f:
                json.dump(cal, f, indent=2)
        if lib:
            env = preload_env(lib, offset)
        cmd = smpirun_command(a.ranks, platform, tmp, a.coll, a.cfg, exe, args, cal)
        t0 = time.monotonic()
        # SimGrid reports a deadlock of the simulated ranks on stderr and smpirun still exits 0:
        # stderr is passed through and watched, and a deadlock is a failure.
        deadlock = False
        with subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, errors="replace",
                              env=env) as proc:
            for line in proc.stderr:
                sys.stderr.write(line)
                deadlock = deadlock or "Deadlock detected" in line
            rc = proc.wait()
        wall = time.monotonic() - t0
        if deadlock and rc == 0:
            print("smpi_run.py: error: SimGrid found the simulated ranks deadlocked", file=sys.stderr)
            rc = 1
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    if rc == 0 and not a.exe:
        stamp_report(args, cal)
    print(f"smpi_run.py: {a.ranks} simulated ranks on {os.path.basename(platform)}: "
          f"wall {wall:.1f} s, peak memory {peak:.0f} MiB, exit {rc}, "
          f"burst charge subtracted {1e6 * offset:.3f} us", flush=True)
    return rc


if __name__ == "__main__":
    sys.exit(main())

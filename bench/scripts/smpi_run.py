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
  smpi/iprobe, smpi/test 1e-7   the simulated cost of one MPI_Iprobe / MPI_Test that finds
                       nothing (~0.1 us, a poll of a shared-memory queue). SMPI's defaults (1e-4 s
                       and more) charge hypre's set-up, which polls with MPI_Iprobe while it
                       exchanges its assumed partition, seconds of simulated time per step.
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
"""
import argparse
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
            "--cfg=smpi/iprobe:1e-7", "--cfg=smpi/test:1e-7", "--cfg=smpi/send-is-detached-thresh:0"]


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
        hosts = os.path.join(tmp, "hosts.txt")
        write_hostfile(hosts, platform, a.ranks)
        cmd = (["smpirun", "-np", str(a.ranks), "-platform", platform, "-hostfile", hosts,
                "--cfg=smpi/tmpdir:" + tmp, "--log=root.thres:warning"] + SETTINGS +
               ["--cfg=smpi/coll-selector:" + a.coll] + ["--cfg=" + c for c in a.cfg] + [exe] + args)
        t0 = time.monotonic()
        # SimGrid reports a deadlock of the simulated ranks on stderr and smpirun still exits 0:
        # stderr is passed through and watched, and a deadlock is a failure.
        deadlock = False
        with subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, errors="replace") as proc:
            for line in proc.stderr:
                sys.stderr.write(line)
                deadlock = deadlock or "Deadlock detected" in line
            rc = proc.wait()
        wall = time.monotonic() - t0
        if deadlock and rc == 0:
            print("smpi_run.py: error: SimGrid found the simulated ranks deadlocked", file=sys.stderr)
            rc = 1
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    print(f"smpi_run.py: {a.ranks} simulated ranks on {os.path.basename(platform)}: "
          f"wall {wall:.1f} s, peak memory {peak:.0f} MiB, exit {rc}", flush=True)
    return rc


if __name__ == "__main__":
    sys.exit(main())

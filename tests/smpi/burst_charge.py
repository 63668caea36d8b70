#!/usr/bin/env python3
"""The charge of an empty burst (docs/smpi.md), test smpi_burst_charge: 2 simulated ranks that
only exchange (bench/smpi/empty_bursts.cpp), simulated three ways by smpi_run.py: the network
alone (no burst charged), SMPI's own charge (--burst-charge none), and the default (the measured
charge of an empty burst subtracted from every burst). With the correction, what an exchange
costs above the network alone must be at most half of what SMPI charges without it (the
development VM: 0.2 against 2.1 us); and a --burst-charge that is not measured, none or a
number of seconds >= 0 is refused by name; and the simulation's heap settings (smpi_run.py's
MALLOC_MMAP_THRESHOLD_ 32 MiB, MALLOC_TRIM_THRESHOLD_ 64 GiB) are given unless the environment
sets them.

    tests/smpi/burst_charge.py --smpi-build BUILD
"""
import argparse
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SMPI_RUN = os.path.join(HERE, "..", "..", "bench", "scripts", "smpi_run.py")


def exchange_us(build, *extra):
    cmd = [sys.executable, SMPI_RUN, "--ranks", "2", "--smpi-build", build, "--exe",
           os.path.join(build, "smpi_empty_bursts")] + list(extra) + ["--", "20000"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    m = re.search(r"([0-9.]+) us an exchange", out.stdout)
    if out.returncode != 0 or not m:
        sys.stdout.write(out.stdout + out.stderr)
        sys.exit(f"burst_charge.py: FAIL: {' '.join(extra)} did not run")
    return float(m.group(1)), out.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--smpi-build", required=True)
    a = ap.parse_args()
    net, _ = exchange_us(a.smpi_build, "--burst-charge", "none", "--cfg",
                         "smpi/simulate-computation:no")
    smpi, _ = exchange_us(a.smpi_build, "--burst-charge", "none")
    corrected, text = exchange_us(a.smpi_build)
    m = re.search(r"an empty burst is charged ([0-9.]+) us", text)
    print(f"network alone {net:.3f} us, SMPI's charge {smpi:.3f} us, corrected {corrected:.3f} us "
          f"an exchange; measured charge of an empty burst {m.group(1) if m else '?'} us")
    ok = m is not None and float(m.group(1)) > 0
    ok = ok and corrected - net <= 0.5 * (smpi - net) + 0.05
    bad = subprocess.run([sys.executable, SMPI_RUN, "--ranks", "2", "--smpi-build", a.smpi_build,
                          "--burst-charge=-1e-6", "--", "run"], capture_output=True, text=True)
    refused = bad.returncode != 0 and "--burst-charge" in bad.stderr
    print(f"--burst-charge=-1e-6: exit {bad.returncode}, {bad.stderr.strip().splitlines()[-1:]}")
    sys.path.insert(0, os.path.dirname(SMPI_RUN))
    import smpi_run
    os.environ.pop("MALLOC_MMAP_THRESHOLD_", None)
    os.environ["MALLOC_TRIM_THRESHOLD_"] = "12345"
    env = smpi_run.simulation_env()
    heap = (env.get("MALLOC_MMAP_THRESHOLD_") == str(32 << 20)
            and env.get("MALLOC_TRIM_THRESHOLD_") == "12345")
    print(f"heap settings: mmap threshold {env.get('MALLOC_MMAP_THRESHOLD_')}, trim threshold "
          f"{env.get('MALLOC_TRIM_THRESHOLD_')} (12345 set in the environment)")
    if ok and refused and heap:
        print("burst_charge.py: PASS")
        return 0
    print("burst_charge.py: FAIL")
    return 1


if __name__ == "__main__":
    sys.exit(main())

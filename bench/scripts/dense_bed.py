#!/usr/bin/env python3
"""A bed that starts in contact, for timing a case's contacts without a restart (SMPI runs).

    bench/scripts/dense_bed.py bench/cases/case3-small.json [--overlap 0.01]
    -> particles.sources=[{"type": "lattice", ...}]      (one argument for coloc's --set)

Reads the case's first source that has a `count` and a `radius` (case 3's layered bed) and
replaces it by a simple-cubic lattice of the same radius and (at least) the same count, its
spacing d (1 - overlap): every particle away from the bed's surface touches its six neighbours
from the first step (4-6 contacts a particle on average, the surface included), where the
layered source leaves a 5 % gap and needs a settling run written as a checkpoint, which the
SimGrid build cannot read (no HDF5). The lattice fills the source's box across and stacks
along its `axis` (z by default) from the source's low corner; it must fit in the box.

    bench/scripts/smpi_scaling.py bench/cases/case3-small.json --dense-bed ...
    coloc run bench/cases/case3-small.json --set "$(bench/scripts/dense_bed.py bench/cases/case3-small.json)"
"""
import argparse
import json
import math
import re
import sys

AXES = "xyz"


def load_case(path):
    """The case file as JSON (its // comment lines dropped)."""
    text = open(path).read()
    return json.loads(re.sub(r"^\s*//.*$", "", text, flags=re.M))


def dense_source(case, overlap=0.01, spread=0.01):
    """The lattice source replacing the case's bed; raises ValueError when it does not fit."""
    srcs = case.get("particles", {}).get("sources", [])
    k = next((i for i, s in enumerate(srcs) if "count" in s and "radius" in s), None)
    if k is None:
        raise ValueError("no source with 'count' and 'radius' (a bed) in particles.sources")
    s = srcs[k]
    if "size" in s:
        raise ValueError("the bed has a size distribution; the lattice holds one radius")
    r, count = float(s["radius"]), int(s["count"])
    length = case["domain"]["length"]
    lo = [float(v) for v in s.get("lo", [0.0, 0.0, 0.0])]
    hi = [float(v) for v in s.get("hi", length)]
    up = AXES.index(s.get("axis", "z"))
    pitch = 2.0 * r * (1.0 - overlap)
    margin = 1e-3 * r  # off the walls by a hair: the lattice's outer spheres must not touch them
    counts = [0, 0, 0]
    for a in range(3):
        if a != up:
            counts[a] = int(math.floor((hi[a] - lo[a] - 2 * r - 2 * margin) / pitch)) + 1
            if counts[a] < 1:
                raise ValueError(f"the source's box is narrower than a sphere along {AXES[a]}")
    layer = counts[(up + 1) % 3] * counts[(up + 2) % 3]
    counts[up] = -(-count // layer)
    top = lo[up] + margin + r + (counts[up] - 1) * pitch + r
    if top > hi[up]:
        raise ValueError(f"{count} spheres at pitch {pitch:g} stack to {top:g} > {hi[up]:g} "
                         f"along {AXES[up]}")
    out = {"type": "lattice", "lo": [lo[a] + r + margin for a in range(3)], "counts": counts,
           "spacing": [pitch] * 3, "radius": r, "velocity_spread": spread}
    if "material" in s:
        out["material"] = s["material"]
    return srcs[:k] + [out] + srcs[k + 1:]


def set_argument(case_path, overlap=0.01):
    """The value of one coloc --set that swaps the case's bed for the dense lattice."""
    return "particles.sources=" + json.dumps(dense_source(load_case(case_path), overlap),
                                             separators=(",", ":"))


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case")
    ap.add_argument("--overlap", type=float, default=0.01,
                    help="overlap of neighbours as a fraction of the diameter (default 0.01)")
    a = ap.parse_args()
    try:
        print(set_argument(a.case, a.overlap))
    except (ValueError, KeyError, OSError) as e:
        sys.exit(f"dense_bed.py: {a.case}: {e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Imbalance and traffic of uniform, balanced and tiled from `coloc plan` outputs (plan.json)."""
import json
import sys


def main(paths):
    print("| case | ranks | uniform | balanced | tiled | floor | inter-physics remote MB/step "
          "(balanced / tiled) | fluid halo MB/step (balanced / tiled) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for path in paths:
        plan = json.load(open(path))
        by = {}
        for l in plan["layouts"]:
            by[(l["strategy"], l["ranks"])] = l
        for n in sorted({r for _, r in by}):
            def imb(s):
                l = by.get((s, n))
                return "refused" if l is None or "error" in l else "%.3f" % l["imbalance"]

            def mb(s, kinds):
                l = by.get((s, n))
                if l is None or "error" in l:
                    return "-"
                t = l["per_step_total"]
                return "%.3f" % (sum(t[k]["bytes"] for k in kinds) / 1e6)

            t = by.get(("tiled", n))
            floor = "-" if t is None or "error" in t else "%.3f" % max(1.0, t["imbalance_floor"])
            inter = ("deposit_sum", "proxy")
            halo = ("fluid_halo", "coupling_halo")
            print("| %s | %d | %s | %s | %s | %s | %s / %s | %s / %s |" % (
                plan["case"], n, imb("uniform"), imb("balanced"), imb("tiled"), floor,
                mb("balanced", inter), mb("tiled", inter), mb("balanced", halo), mb("tiled", halo)))


if __name__ == "__main__":
    main(sys.argv[1:])

#!/usr/bin/python3
"""No share without bytes: every CSV behind the committed plots (scaling.csv, strategies.csv)
books inter-physics exchange time only where bytes moved.

    /usr/bin/python3 bench/scripts/check_shares.py [CSV ...]   # default: bench/results/*/*.csv

Per row: an across-ranks share (frac_inter_remote) > 0 needs inter-physics bytes sent across
ranks (inter_remote_bytes or inter_remote_bytes_per_step); an inside-a-rank share
(frac_inter_local) > 0 needs inside-a-rank bytes; the total share (frac_inter_physics) > 0 needs
one or the other. Exit status 1 with the offending rows, 0 otherwise.
"""
import csv
import glob
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def num(row, *keys):
    for k in keys:
        if row.get(k) not in (None, ""):
            return float(row[k])
    return None


def problems(path):
    out = []
    with open(path) as f:
        for i, r in enumerate(csv.DictReader(f), start=2):
            if "frac_inter_physics" not in r:
                continue
            remote = num(r, "inter_remote_bytes", "inter_remote_bytes_per_step") or 0.0
            local = num(r, "inter_local_bytes", "inter_local_bytes_per_step") or 0.0
            tag = f"{path}:{i} ({r.get('mode') or r.get('strategy')}, {r.get('ranks')} ranks)"
            if (num(r, "frac_inter_remote") or 0.0) > 0 and remote == 0:
                out.append(f"{tag}: across-ranks share {r['frac_inter_remote']} with 0 bytes across ranks")
            if (num(r, "frac_inter_local") or 0.0) > 0 and local == 0:
                out.append(f"{tag}: inside-a-rank share {r['frac_inter_local']} with 0 bytes inside")
            if (num(r, "frac_inter_physics") or 0.0) > 0 and remote == 0 and local == 0:
                out.append(f"{tag}: inter-physics share {r['frac_inter_physics']} with 0 bytes")
    return out


def main():
    paths = sys.argv[1:] or sorted(glob.glob(os.path.join(ROOT, "bench", "results", "*", "*.csv")))
    if not paths:
        print("check_shares: no CSV found", file=sys.stderr)
        return 1
    bad = [p for path in paths for p in problems(path)]
    for b in bad:
        print("check_shares: FAIL:", b)
    if not bad:
        print(f"check_shares: PASS: {len(paths)} CSV files, no share without bytes")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Tile the settled 100k DEM bed (periodic in x and y) into a larger settled bed.

The bed of bench/cases/dem-bed.json is periodic in x and y, so nx x ny copies side by side are a
settled bed of nx*ny times the particles with the same contacts (across the seams too: a contact
that crossed a periodic face of the small box now joins two neighbouring copies). Both files that
bench_dem writes are tiled:

  state (DEM_BED_SAVE, binary doubles): n, contacts, time, steps, rebuilds; n records of 22
        (id, material, radius, mass, x, v, omega, f, torque, fExt); contacts of 5
        (holder id, partner id or -1-wall, shear 3)
  data  (DEM_BED_DUMP, LAMMPS/LIGGGHTS data file, atom_style granular)

Copy t = tx + nx*ty gets ids id + t*n and positions shifted by (tx Lx, ty Ly). The 1M bed of
bench/cases/dem-bed-1m.json is nx = 5, ny = 2:

  dem_bed_tile.py --nx 5 --ny 2 --state bed.state --data bed.data \
      --out-state bed1m.state --out-data bed1m.data
"""
import argparse

import numpy as np

REC = 22


def tile_state(src, dst, nx, ny, L):
    raw = np.fromfile(src, dtype=np.float64)
    n, nc = int(raw[0]), int(raw[1])
    head = raw[:5].copy()
    rec = raw[5:5 + n * REC].reshape(n, REC)
    con = raw[5 + n * REC:5 + n * REC + 5 * nc].reshape(nc, 5)
    ids = rec[:, 0].astype(np.int64)
    if ids.min() < 0 or ids.max() >= n:
        raise SystemExit("ids are expected in [0, n)")
    pos = np.zeros((n, 3))
    pos[ids] = rec[:, 4:7]
    out_rec, out_con = [], []
    h = con[:, 0].astype(np.int64)
    pa = con[:, 1].astype(np.int64)
    wall = pa < 0
    # the partner's copy: the neighbouring one when the pair crossed a periodic face
    off = np.zeros((nc, 2), dtype=np.int64)
    for d in range(2):
        dx = np.where(wall, 0.0, pos[np.where(wall, 0, pa), d] - pos[h, d])
        off[:, d] = np.where(dx > 0.5 * L[d], -1, np.where(dx < -0.5 * L[d], 1, 0))
    for ty in range(ny):
        for tx in range(nx):
            t = tx + nx * ty
            r = rec.copy()
            r[:, 0] += t * n
            r[:, 4] += tx * L[0]
            r[:, 5] += ty * L[1]
            out_rec.append(r)
            c = con.copy()
            c[:, 0] += t * n
            px = (tx + off[:, 0]) % nx
            py = (ty + off[:, 1]) % ny
            c[:, 1] = np.where(wall, con[:, 1], con[:, 1] + (px + nx * py) * n)
            out_con.append(c)
    head[0] = n * nx * ny
    head[1] = nc * nx * ny
    np.concatenate([head, np.concatenate(out_rec).ravel(),
                    np.concatenate(out_con).ravel()]).tofile(dst)
    return n


def tile_data(src, dst, nx, ny):
    lines = open(src).read().split("\n")
    n = int(lines[2].split()[0])
    lo, hi = {}, {}
    for ln in lines[:12]:
        f = ln.split()
        if len(f) == 4 and f[2].endswith("lo"):
            ax = f[2][0]
            lo[ax], hi[ax] = float(f[0]), float(f[1])
    L = [hi["x"] - lo["x"], hi["y"] - lo["y"]]
    ia = lines.index("Atoms")
    iv = lines.index("Velocities")
    atoms = [ln.split() for ln in lines[ia + 2:ia + 2 + n]]
    vels = [ln.split() for ln in lines[iv + 2:iv + 2 + n]]
    with open(dst, "w") as out:
        out.write("coloc dem-bed settled state, tiled %d x %d\n\n%d atoms\n1 atom types\n\n"
                  % (nx, ny, n * nx * ny))
        out.write("%r %r xlo xhi\n" % (lo["x"], lo["x"] + nx * L[0]))
        out.write("%r %r ylo yhi\n" % (lo["y"], lo["y"] + ny * L[1]))
        out.write("%r %r zlo zhi\n" % (lo["z"], hi["z"]))
        out.write("\nAtoms\n\n")
        for ty in range(ny):
            for tx in range(nx):
                t = tx + nx * ty
                for a in atoms:
                    out.write("%d %s %s %s %r %r %s\n" % (
                        int(a[0]) + t * n, a[1], a[2], a[3], float(a[4]) + tx * L[0],
                        float(a[5]) + ty * L[1], a[6]))
        out.write("\nVelocities\n\n")
        for ty in range(ny):
            for tx in range(nx):
                t = tx + nx * ty
                for v in vels:
                    out.write("%d %s\n" % (int(v[0]) + t * n, " ".join(v[1:])))
    return L


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=5)
    ap.add_argument("--ny", type=int, default=2)
    ap.add_argument("--lx", type=float, default=0.05, help="box length along x of the small bed")
    ap.add_argument("--ly", type=float, default=0.05)
    ap.add_argument("--state")
    ap.add_argument("--data")
    ap.add_argument("--out-state")
    ap.add_argument("--out-data")
    a = ap.parse_args()
    if a.state:
        n = tile_state(a.state, a.out_state, a.nx, a.ny, [a.lx, a.ly])
        print("state: %d -> %d particles" % (n, n * a.nx * a.ny))
    if a.data:
        tile_data(a.data, a.out_data, a.nx, a.ny)
        print("data file written")


if __name__ == "__main__":
    main()

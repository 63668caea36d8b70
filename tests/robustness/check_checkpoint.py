#!/usr/bin/env python3
"""check_checkpoint.py CHECKPOINT.h5 FIELDS.h5 PARTICLES.h5

Reads a checkpoint back with h5py and compares it with the run's regular output of the same step
(written from the in-memory state by OutputWriter, through another code path): p, eps and K
exactly, the cell-centred velocity as the mean of the checkpoint's face velocities (the solver's
own arithmetic, so exactly), and the particles' x, v, omega and radius after sorting by id. Also
checks the layout: attributes, shapes of the staggered arrays, one row per particle, status ok."""
import sys

import h5py
import numpy as np


def s(v):
    return v.decode() if isinstance(v, bytes) else v


def main():
    ck, fields, parts = (h5py.File(p, "r") for p in sys.argv[1:4])
    fails = []

    def check(cond, msg):
        if not cond:
            fails.append(msg)
            print("FAIL:", msg)

    check(s(ck.attrs["format"]) == "coloc-checkpoint", "format attribute")
    check(s(ck.attrs["status"]) == "ok", f"status {s(ck.attrs['status'])!r}")
    check(ck.attrs["step"] == fields.attrs["step"], "step differs from the output's")
    check(ck.attrs["time"] == fields.attrs["time"], "time differs from the output's")
    cells = [int(c) for c in ck["grid"].attrs["cells"]]
    periodic = [bool(p) for p in ck["grid"].attrs["periodic"]]
    nx, ny, nz = cells
    check(list(fields.attrs["cells"]) == cells, "grid differs from the output's")
    f = ck["fluid"]
    for name in ("p", "eps", "K"):
        check(f[name].shape == (nz, ny, nx), f"/fluid/{name} shape {f[name].shape}")
        check(np.array_equal(f[name][...], fields[name][...]), f"/fluid/{name} != output {name}")
    check(f["KUp"].shape == (nz, ny, nx, 3), "/fluid/KUp shape")
    # Face arrays: one more face along a closed axis. Cell velocity = mean of the two faces.
    uc = fields["u"][...]
    for d, name in enumerate(("u_x", "u_y", "u_z")):
        shape = [nz, ny, nx]
        axis = 2 - d
        if not periodic[d]:
            shape[axis] += 1
        u = f[name][...]
        check(list(u.shape) == shape, f"/fluid/{name} shape {u.shape}, expected {shape}")
        check(list(f["H_" + name[-1]].shape) == shape, f"/fluid/H_{name[-1]} shape")
        lo = u
        hi = np.roll(u, -1, axis=axis) if periodic[d] else np.delete(u, 0, axis=axis)
        if not periodic[d]:
            lo = np.delete(u, u.shape[axis] - 1, axis=axis)
        mean = 0.5 * (lo + hi)
        check(np.array_equal(mean, uc[..., d]), f"mean of /fluid/{name} != output u[{d}]")
    p = ck["particles"]
    n = int(p.attrs["count"])
    check(n == int(parts.attrs["count"]), "particle count differs from the output's")
    ia, ib = np.argsort(p["id"][...]), np.argsort(parts["id"][...])
    check(np.array_equal(p["id"][...][ia], parts["id"][...][ib]), "ids differ")
    for name in ("x", "v", "omega", "radius"):
        check(np.array_equal(p[name][...][ia], parts[name][...][ib]),
              f"/particles/{name} != output {name}")
    for name in ("f", "torque", "f_ext", "x", "v", "omega"):
        check(p[name].shape == (n, 3), f"/particles/{name} shape")
    for name in ("mass", "radius", "material", "id"):
        check(p[name].shape == (n,), f"/particles/{name} shape")
    c = p["contacts"]
    m = int(c.attrs["count"])
    check(c["holder"].shape == (m,) and c["shear"].shape == (m, 3), "contact arrays")
    ids = set(p["id"][...].tolist())
    check(all(h in ids for h in c["holder"][...].tolist()), "a contact holder is not a particle")
    check(m > 0, "no contact histories (the bed should have some)")
    cuts = [ck["partition/fluid"].attrs["cuts_" + a] for a in "xyz"]
    check(all(cc[0] == 0 and cc[-1] == cells[i] for i, cc in enumerate(cuts)), "cuts")
    print("FAILED" if fails else "OK", f"{sys.argv[1]}: {n} particles, {m} contacts")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""compare_checkpoints.py A.h5 B.h5 [--rtol R]

Compares two coloc checkpoints (coupling/checkpoint.hpp) value by value, independently of the
rank count and particle order that wrote them: the fluid arrays as they are (global arrays), the
particles and the contact histories after sorting by id, the counters of /simulation and the
step/time/status attributes. --rtol 0 (the default) asks for identical values (bitwise, NaN equal
to NaN); otherwise |a - b| <= rtol * max|a| per array. Exit status 0 when they agree."""
import argparse
import sys

import h5py
import numpy as np

FAILS = []


def fail(msg):
    FAILS.append(msg)
    print("FAIL:", msg)


def close(name, a, b, rtol):
    a = np.asarray(a)
    b = np.asarray(b)
    if a.shape != b.shape:
        fail(f"{name}: shapes {a.shape} vs {b.shape}")
        return
    if a.size == 0:
        return
    if rtol == 0 or a.dtype.kind in "iub":
        same = np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
        if not same:
            d = np.abs(a.astype(float) - b.astype(float))
            i = np.unravel_index(np.nanargmax(d), d.shape)
            fail(f"{name}: not identical (max |diff| {np.nanmax(d):.3e} at {i}: {a[i]!r} vs {b[i]!r})")
        return
    scale = max(np.max(np.abs(a)), np.max(np.abs(b)), 1e-300)
    d = np.max(np.abs(a - b))
    if not d <= rtol * scale:
        fail(f"{name}: max |diff| {d:.3e} > {rtol:g} * {scale:.3e}")


def attr(f, obj, name):
    v = f[obj].attrs[name]
    return v.decode() if isinstance(v, bytes) else v


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--rtol", type=float, default=0.0)
    args = ap.parse_args()
    fa, fb = h5py.File(args.a, "r"), h5py.File(args.b, "r")
    for f, p in ((fa, args.a), (fb, args.b)):
        if attr(f, "/", "format") != "coloc-checkpoint":
            fail(f"{p}: not a coloc checkpoint")
    for k in ("status", "step", "mode", "case"):
        if attr(fa, "/", k) != attr(fb, "/", k):
            fail(f"/@{k}: {attr(fa, '/', k)!r} vs {attr(fb, '/', k)!r}")
    close("/@time", attr(fa, "/", "time"), attr(fb, "/", "time"), args.rtol)
    # Counters of the simulation (integers exact; reals to rtol).
    for k in fa["/simulation"].attrs:
        if args.rtol and k == "momentum_residual":
            continue  # a round-off-sized residual: only its order of magnitude is reproducible
        close(f"/simulation@{k}", attr(fa, "/simulation", k), attr(fb, "/simulation", k), args.rtol)
    if "fluid" in fa:
        for k in fa["/fluid"].attrs:
            if k in ("setups",):
                continue  # hypre set-ups: a restored run sets the matrix up once more
            if args.rtol and k in ("iterations_sum", "iterations_max", "iterations_last", "solves",
                                   "residual_last", "rhs_scale_last", "steady_residual"):
                continue  # solver iterations depend on the blocks
            close(f"/fluid@{k}", attr(fa, "/fluid", k), attr(fb, "/fluid", k), args.rtol)
        for k in fa["/fluid"]:
            close(f"/fluid/{k}", fa["/fluid"][k][...], fb["/fluid"][k][...], args.rtol)
    if "particles" in fa:
        pa, pb = fa["/particles"], fb["/particles"]
        ia, ib = np.argsort(pa["id"][...]), np.argsort(pb["id"][...])
        close("/particles/id", pa["id"][...][ia], pb["id"][...][ib], 0)
        for k in pa:
            if k in ("contacts", "id"):
                continue
            close(f"/particles/{k}", pa[k][...][ia], pb[k][...][ib], args.rtol)
        for k in ("time", "steps", "count"):
            close(f"/particles@{k}", attr(fa, "/particles", k), attr(fb, "/particles", k), args.rtol)
        ca, cb = pa["contacts"], pb["contacts"]
        ka = list(zip(ca["holder"][...], ca["partner"][...]))
        kb = list(zip(cb["holder"][...], cb["partner"][...]))
        oa = sorted(range(len(ka)), key=lambda i: ka[i])
        ob = sorted(range(len(kb)), key=lambda i: kb[i])
        if args.rtol == 0:
            if [ka[i] for i in oa] != [kb[i] for i in ob]:
                fail(f"/particles/contacts: different pairs ({len(ka)} vs {len(kb)})")
            else:
                for k in ("shear", "roll"):
                    close(f"/particles/contacts/{k}", ca[k][...][oa], cb[k][...][ob], 0)
        else:
            common = sorted(set(ka) & set(kb))
            if len(common) < 0.99 * max(len(ka), len(kb)):
                fail(f"/particles/contacts: {len(ka)} vs {len(kb)} pairs, {len(common)} common")
            ma = {k: i for i, k in enumerate(ka)}
            mb = {k: i for i, k in enumerate(kb)}
            for k in ("shear", "roll"):
                close(f"/particles/contacts/{k}", ca[k][...][[ma[c] for c in common]],
                      cb[k][...][[mb[c] for c in common]], args.rtol)
    print(("FAILED" if FAILS else "OK"), f"{args.a} vs {args.b} (rtol {args.rtol:g}),",
          len(FAILS), "difference(s)")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())

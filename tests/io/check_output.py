#!/usr/bin/python3
"""Check an output series written by io_write_series (see write_series.cpp for the formulas).

    check_output.py DIR RANKS

Opens DIR/fields.xmf and DIR/particles.xmf with xml.etree, checks that they are temporal
collections of the expected steps, that every DataItem points at an existing HDF5 file and
dataset whose shape and number type match the XDMF, that the mesh (3DCoRectMesh, points in
z y x order) matches the grid, and compares every value with the formula. Exit status 1 with a
list of problems on failure.
"""
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

CELLS = (7, 5, 4)  # x, y, z
ORIGIN = (0.5, -1.0, 2.0)
SPACING = (0.2, 0.25, 0.5)
STEPS = (0, 5, 10)

problems = []


def check(cond, msg):
    if not cond:
        problems.append(msg)
    return cond


def matches(a, want, atol=0.0):
    """Same shape and values (exactly, or within atol)."""
    a, want = np.asarray(a), np.asarray(want)
    if a.shape != want.shape:
        return False
    return np.array_equal(a, want) if atol == 0 else np.allclose(a, want, rtol=0, atol=atol)


def dims(text):
    return tuple(int(v) for v in text.split())


def resolve(xmf_dir, item):
    """DataItem -> (h5py dataset, its file), after checking the reference and the shape/type."""
    fmt = item.get("Format")
    ref = item.text.strip()
    if not check(fmt == "HDF", f"DataItem {ref}: Format {fmt}, expected HDF"):
        return None
    fname, _, dset = ref.partition(":")
    path = os.path.join(xmf_dir, fname)
    if not check(os.path.isfile(path), f"{ref}: no file {path}"):
        return None
    f = h5py.File(path, "r")
    if not check(dset in f, f"{ref}: no dataset {dset} in {fname}"):
        return None
    d = f[dset]
    want = dims(item.get("Dimensions"))
    check(d.shape == want, f"{ref}: shape {d.shape}, XDMF says {want}")
    ntype, prec = item.get("NumberType", "Float"), int(item.get("Precision", "4"))
    kind = {"Float": "f", "Int": "i", "UInt": "u"}.get(ntype)
    check(d.dtype.kind == kind and d.dtype.itemsize == prec,
          f"{ref}: dtype {d.dtype}, XDMF says {ntype}/{prec}")
    return d


def series(xmf):
    check(os.path.isfile(xmf), f"missing {xmf}")
    root = ET.parse(xmf).getroot()
    check(root.tag == "Xdmf", f"{xmf}: root <{root.tag}>")
    coll = root.find("Domain/Grid")
    check(coll is not None and coll.get("GridType") == "Collection"
          and coll.get("CollectionType") == "Temporal", f"{xmf}: not a temporal collection")
    grids = coll.findall("Grid")
    times = [float(g.find("Time").get("Value")) for g in grids]
    check(times == sorted(times), f"{xmf}: times not increasing: {times}")
    check(len(grids) == len(STEPS), f"{xmf}: {len(grids)} steps, expected {len(STEPS)}")
    return grids


def attribute_items(grid, center):
    out = {}
    for a in grid.findall("Attribute"):
        check(a.get("Center") == center, f"attribute {a.get('Name')}: Center {a.get('Center')}")
        out[a.get("Name")] = (a.get("AttributeType"), a.find("DataItem"))
    return out


def check_fields(d, ranks):
    xmf = os.path.join(d, "fields.xmf")
    nx, ny, nz = CELLS
    i = np.arange(nx)[None, None, :]
    j = np.arange(ny)[None, :, None]
    k = np.arange(nz)[:, None, None]
    for g, step in zip(series(xmf), STEPS):
        t = float(g.find("Time").get("Value"))
        check(abs(t - 0.01 * step) < 1e-15, f"fields step {step}: time {t}")
        topo = g.find("Topology")
        check(topo.get("TopologyType") == "3DCoRectMesh", "fields: topology type")
        check(dims(topo.get("Dimensions")) == (nz + 1, ny + 1, nx + 1),
              f"fields: topology Dimensions {topo.get('Dimensions')} (points, z y x)")
        geo = g.find("Geometry")
        check(geo.get("GeometryType") == "ORIGIN_DXDYDZ", "fields: geometry type")
        o, s = [np.array([float(v) for v in it.text.split()]) for it in geo.findall("DataItem")]
        check(np.allclose(o, ORIGIN[::-1], rtol=0, atol=1e-14), f"fields: origin {o} (z y x)")
        check(np.allclose(s, SPACING[::-1], rtol=0, atol=1e-14), f"fields: spacing {s} (z y x)")
        attrs = attribute_items(g, "Cell")
        check(set(attrs) == {"p", "u", "rank"}, f"fields: attributes {sorted(attrs)}")
        kind, item = attrs["rank"]
        owner = resolve(d, item)
        check(kind == "Scalar", "rank: not Scalar")
        if owner is not None:
            o = owner[...]
            check(set(np.unique(o).tolist()) == set(float(r) for r in range(ranks)),
                  f"rank at step {step}: owners {np.unique(o).tolist()}, {ranks} ranks")
        kind, item = attrs["p"]
        p = resolve(d, item)
        check(kind == "Scalar", "p: not Scalar")
        if p is not None:
            check(p.file.attrs["step"] == step and p.file.attrs["time"] == t,
                  f"{p.file.filename}: step/time attributes")
            want = i + 10.0 * j + 100.0 * k + 1000.0 * step
            check(matches(p[...], want), f"p at step {step}: values differ from the formula")
        kind, item = attrs["u"]
        u = resolve(d, item)
        check(kind == "Vector", "u: not Vector")
        if u is not None:
            for c, idx in enumerate((i, j, k)):
                want = ORIGIN[c] + (idx + 0.5) * SPACING[c] + step + 0 * (i + j + k)
                check(matches(u[..., c], want, 1e-12),
                      f"u[{c}] at step {step}: values differ from the formula")


def check_particles(d, ranks):
    xmf = os.path.join(d, "particles.xmf")
    counts = [0 if (ranks > 1 and r == 1) else 2 + 3 * r for r in range(ranks)]
    rr = np.concatenate([np.full(n, r) for r, n in enumerate(counts)])
    qq = np.concatenate([np.arange(n) for n in counts]).astype(float)
    n = len(rr)
    for g, step in zip(series(xmf), STEPS):
        topo = g.find("Topology")
        check(topo.get("TopologyType") == "Polyvertex", "particles: topology type")
        check(int(topo.get("NumberOfElements")) == n,
              f"particles: NumberOfElements {topo.get('NumberOfElements')}, expected {n}")
        geo = g.find("Geometry")
        check(geo.get("GeometryType") == "XYZ", "particles: geometry type")
        x = resolve(d, geo.find("DataItem"))
        if x is not None:
            want = np.stack([0.6 + 0.1 * qq, -0.9 + 0.1 * rr, 2.1 + 0.01 * step + 0 * qq], axis=1)
            check(matches(x[...], want, 1e-14), f"x at step {step}: values differ")
            check(x.file.attrs["count"] == n, "particles: count attribute")
        attrs = attribute_items(g, "Node")
        check(set(attrs) == {"id", "v", "omega", "radius", "rank"},
              f"particles: attributes {sorted(attrs)}")
        vel = np.stack([qq, rr.astype(float), step + 0 * qq], axis=1)
        expect = {
            "id": ("Scalar", 1000 * rr + qq.astype(np.int64) + 2**40),
            "v": ("Vector", vel),
            "omega": ("Vector", -vel),
            "radius": ("Scalar", 0.01 * (1 + qq)),
            "rank": ("Scalar", rr),
        }
        for name, (kind, want) in expect.items():
            if name not in attrs:
                continue
            check(attrs[name][0] == kind, f"{name}: AttributeType {attrs[name][0]}")
            a = resolve(d, attrs[name][1])
            if a is not None:
                check(matches(a[...], want), f"{name} at step {step}: values differ")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: check_output.py DIR RANKS")
    d, ranks = sys.argv[1], int(sys.argv[2])
    check_fields(d, ranks)
    check_particles(d, ranks)
    leftovers = [f for f in os.listdir(d) if f.endswith(".tmp")]
    check(not leftovers, f"temporary files left: {leftovers}")
    if problems:
        print("\n".join(problems))
        sys.exit(1)
    print(f"check_output: {d} OK ({len(STEPS)} field and particle outputs, {ranks} rank(s))")


if __name__ == "__main__":
    main()

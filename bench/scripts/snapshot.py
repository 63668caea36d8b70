#!/usr/bin/python3
"""A picture of a run without ParaView: DIR/snapshot.png from the last output of DIR.

    /usr/bin/python3 bench/scripts/snapshot.py OUT_DIR [--step N] [--png FILE] [--report FILE]
                                                        [--full]

Left: the fluid fraction eps on the mid-plane that contains the vertical (gravity) axis; right:
the fluid speed |u| (m/s) on the same plane. The particles whose centres lie within one cell of
the plane are drawn on both, to scale (their true radius), coloured by the rank that owns them on
the left and by their speed on the right. The blocks of the partition (report.json
partition.boxes: the fluid's block of every rank, process grid or tiled boxes) that the plane
cuts are drawn on both as white lines, numbered by rank up to 64 ranks. A bed under a tall
freeboard (the particles below 70 % of the box height) is drawn up to a margin above its highest
particle, and above every block face the plane cuts (the blocks stay whole in view), said in the
title; --full draws the whole box.
Reads the files of docs/output.md with h5py (fields_NNNNNN.h5, particles_NNNNNN.h5) and the
case's gravity from report.json when it is there (else: the longest axis is vertical). The coloc
driver runs this at the end of a run that writes fields (key output.snapshot). Exit status 0
when the PNG is written; 2 for a --step that has no output (the message lists the steps that
have); 1 with a message otherwise.
"""
import argparse
import glob
import json
import os
import re
import sys
import tempfile


def output_steps(out_dir, series):
    """The steps of OUT_DIR/SERIES_NNNNNN.h5, sorted."""
    steps = []
    for f in glob.glob(os.path.join(out_dir, series + "_*.h5")):
        m = re.search(r"_(\d+)\.h5$", f)
        if m:
            steps.append(int(m.group(1)))
    return sorted(steps)


def last_step(out_dir, series):
    steps = output_steps(out_dir, series)
    return steps[-1] if steps else None


def steps_text(steps):
    """A list of steps for a message: all of them, or the first and last five of many."""
    if len(steps) <= 12:
        return ", ".join(str(s) for s in steps)
    return "%s, ..., %s (%d steps)" % (", ".join(str(s) for s in steps[:5]),
                                       ", ".join(str(s) for s in steps[-5:]), len(steps))


def crop_top(particles_up, lo, length, spacing, faces):
    """Where the picture of a bed under a freeboard ends along the vertical axis (gravity along
    -up): a margin above the highest particle (a quarter of the particles' height, at least 4
    cells) and 2 cells above the highest block face the plane cuts (`faces`, m, the box's own
    faces excluded), when that leaves out more than 30 % of the box; else the top of the box."""
    top = lo + length
    if len(particles_up) == 0:
        return top
    hi, low = float(max(particles_up)), float(min(particles_up))
    want = hi + max(0.25 * (hi - low), 4 * spacing)
    inner = [f for f in faces if lo < f < top]
    if inner:
        want = max(want, max(inner) + 2 * spacing)
    return want if want < lo + 0.7 * length else top


def png_target_problem(png):
    """Why PNG cannot be written (what is there is not a regular file, or is not a PNG); None
    when it can: coloc replaces only a picture of its own kind, never through a link."""
    if not os.path.lexists(png):
        return None
    if os.path.islink(png) or not os.path.isfile(png):
        return "'%s' exists and is not a regular file (a link, a folder, a FIFO or a device): " \
            "not replaced; remove it or give another --png" % png
    with open(png, "rb") as f:
        if f.read(8) != b"\x89PNG\r\n\x1a\n":
            return "'%s' exists and is not a PNG picture: not replaced; remove it or give " \
                "another --png" % png
    return None


def vertical_axis(report, length):
    """(axis, +1 if up is +axis) from the case's gravity in report.json, else the longest axis."""
    try:
        with open(report) as f:
            g = json.load(f)["config"]["gravity"]
        a = max(range(3), key=lambda d: abs(g[d]))
        if g[a] != 0:
            return a, (1 if g[a] < 0 else -1)
    except (OSError, KeyError, ValueError, TypeError, IndexError):
        pass
    return max(range(3), key=lambda d: length[d]), 1


def partition_boxes(report):
    """(strategy, the fluid's blocks [lo x, y, z, hi x, y, z] in cells) from report.json, or
    (None, []) when it has none (an older report)."""
    try:
        with open(report) as f:
            part = json.load(f)["partition"]
        return part.get("strategy"), part.get("boxes") or []
    except (OSError, KeyError, ValueError, TypeError):
        return None, []


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--step", type=int, help="output step (default: the last one)")
    ap.add_argument("--png", help="output file (default: OUT_DIR/snapshot.png)")
    ap.add_argument("--report", help="the run's report.json (default: OUT_DIR/report.json)")
    ap.add_argument("--full", action="store_true",
                    help="the whole height of the box (default: cropped a margin above the "
                         "highest particle and the block faces when that leaves out more than "
                         "30 %% of the box)")
    args = ap.parse_args()
    try:
        import h5py
        import numpy as np
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import EllipseCollection
    except ImportError as e:
        print("snapshot.py: needs h5py, numpy and matplotlib (/usr/bin/python3 on Debian): %s" % e,
              file=sys.stderr)
        return 1

    steps = output_steps(args.out_dir, "fields")
    if not steps:
        print("snapshot.py: no fields_*.h5 in '%s' (a run writes them with "
              "output.interval_steps > 0)" % args.out_dir, file=sys.stderr)
        return 1
    if args.step is not None and args.step not in steps:
        print("snapshot.py: error: no output at step %d in '%s' (no fields_%06d.h5); the steps "
              "with output: %s" % (args.step, args.out_dir, args.step, steps_text(steps)),
              file=sys.stderr)
        return 2
    step = args.step if args.step is not None else steps[-1]
    fpath = os.path.join(args.out_dir, "fields_%06d.h5" % step)
    png = args.png or os.path.join(args.out_dir, "snapshot.png")
    why = png_target_problem(png)
    if why:
        print("snapshot.py: %s" % why, file=sys.stderr)
        return 1
    try:
        with h5py.File(fpath, "r") as f:
            origin = np.array(f.attrs["origin"], dtype=float)
            spacing = np.array(f.attrs["spacing"], dtype=float)
            cells = np.array(f.attrs["cells"], dtype=float).astype(int)
            time = float(f.attrs["time"])
            eps = f["eps"][...] if "eps" in f else None      # [nz][ny][nx]
            u = f["u"][...] if "u" in f else None            # [nz][ny][nx][3]
    except (OSError, KeyError) as e:
        print("snapshot.py: error: cannot read '%s': %s" % (fpath, e), file=sys.stderr)
        return 1
    length = spacing * cells
    report = args.report or os.path.join(args.out_dir, "report.json")
    up, sign = vertical_axis(report, length)
    strategy, boxes = partition_boxes(report)
    # The in-plane horizontal axis: the longer of the other two; the plane is normal to the third.
    others = [d for d in range(3) if d != up]
    horiz = max(others, key=lambda d: length[d])
    normal = [d for d in others if d != horiz][0]
    mid = cells[normal] // 2

    def plane(a):  # a indexed [z][y][x]; returns [vertical][horizontal]
        a = np.take(a, mid, axis=2 - normal)
        rem = [d for d in (2, 1, 0) if d != normal]  # remaining array axes as grid axes
        return a if rem[0] == up else a.T

    panels = []
    if eps is not None:
        panels.append(("fluid fraction eps (1)", plane(eps), "viridis"))
    if u is not None:
        panels.append(("fluid speed |u| (m/s)", plane(np.linalg.norm(u, axis=-1)), "magma"))
    if not panels:
        print("snapshot.py: '%s' has neither eps nor u" % fpath, file=sys.stderr)
        return 1

    ppath = os.path.join(args.out_dir, "particles_%06d.h5" % step)
    px = None
    if os.path.exists(ppath):
        try:
            with h5py.File(ppath, "r") as f:
                x, v, r = f["x"][...], f["v"][...], f["radius"][...]
                rank = f["rank"][...] if "rank" in f else np.zeros(len(x), dtype=int)
        except (OSError, KeyError) as e:
            print("snapshot.py: error: cannot read '%s': %s" % (ppath, e), file=sys.stderr)
            return 1
        near = np.abs(x[:, normal] - (origin[normal] + (mid + 0.5) * spacing[normal])) \
            <= spacing[normal]
        px, pv, pr, prank = x[near], np.linalg.norm(v[near], axis=1), r[near], rank[near]
        ntotal = len(x)

    ext = [origin[horiz], origin[horiz] + length[horiz], origin[up], origin[up] + length[up]]
    # Crop the empty freeboard: show up to a margin above the highest particle and above the
    # block faces the plane cuts (crop_top), when that leaves out more than 30 % of the box
    # (gravity along -up only; --full keeps the whole box).
    top = ext[3]
    if px is not None and ntotal and sign > 0 and not args.full:
        faces = [origin[up] + b[k + up] * spacing[up] for b in boxes
                 if b[normal] <= mid < b[3 + normal] for k in (0, 3)]
        top = crop_top(x[:, up], ext[2], length[up], spacing[up], faces)
    aspect = (top - ext[2]) / length[horiz]
    w = 4.0 if aspect > 1.5 else 6.0
    # the panels' axes keep the box's aspect: about 0.78 w wide each, plus titles and colour bars
    fig, axes = plt.subplots(1, len(panels),
                             figsize=(w * len(panels), max(4.0, min(9.0, 0.78 * w * aspect) + 2.4)),
                             squeeze=False, layout="constrained")
    names = "xyz"
    for ax, (title, img, cmap) in zip(axes[0], panels):
        im = ax.imshow(img, origin="lower" if sign > 0 else "upper", extent=ext, cmap=cmap,
                       interpolation="nearest", aspect="equal")
        fig.colorbar(im, ax=ax, orientation="horizontal", shrink=0.9, pad=0.04, label=title)
        if px is not None and len(px):
            speed_panel = title.startswith("fluid speed")
            nranks = max(len(boxes), int(prank.max()) + 1 if len(prank) else 1)
            by_rank = plt.get_cmap("tab20")(prank % 20) if nranks > 1 else "white"
            ec = EllipseCollection(2 * pr, 2 * pr, np.zeros_like(pr), units="xy",
                                   offsets=np.column_stack([px[:, horiz], px[:, up]]),
                                   offset_transform=ax.transData,
                                   facecolors="none" if not speed_panel else None,
                                   edgecolors=by_rank if not speed_panel else "black",
                                   linewidths=0.3 if speed_panel or nranks == 1 else 0.8)
            if speed_panel:
                ec.set_array(pv)
                ec.set_cmap("cool")
                fig.colorbar(ec, ax=ax, orientation="horizontal", shrink=0.9, pad=0.02,
                             label="particle speed |v| (m/s)")
            ax.add_collection(ec)
        for q, b in enumerate(boxes):  # the blocks the plane cuts
            if not b[normal] <= mid < b[3 + normal]:
                continue
            x0 = origin[horiz] + b[horiz] * spacing[horiz]
            y0 = origin[up] + b[up] * spacing[up]
            wdt = (b[3 + horiz] - b[horiz]) * spacing[horiz]
            hgt = (b[3 + up] - b[up]) * spacing[up]
            ax.add_patch(plt.Rectangle((x0, y0), wdt, hgt, fill=False, ec="white", lw=0.8,
                                       ls="--", alpha=0.9))
            ylo, yhi = max(y0, ext[2]), min(y0 + hgt, top)  # the part in view (crop)
            if len(boxes) <= 64 and ylo < yhi:
                ax.text(x0 + wdt / 2, (ylo + yhi) / 2, str(q), color="white", fontsize=7,
                        ha="center", va="center", alpha=0.9)
        ax.set_ylim(ext[2], top)
        ax.set_xlabel("%s (m)" % names[horiz])
        ax.tick_params(axis="x", labelrotation=30)
        ax.set_ylabel("%s (m), %s" % (names[up], "up" if sign > 0 else "down"))
        ax.set_title(title.split(" (")[0], fontsize=10)
    case = os.path.basename(os.path.normpath(args.out_dir))
    sub = "plane %s = %.4g m (cell %d)" % (names[normal],
                                            origin[normal] + (mid + 0.5) * spacing[normal], mid)
    if px is not None:
        sub += "; %d of %d particles within one cell of it, drawn to scale" % (len(px), ntotal)
    if top < ext[3]:
        sub += "\ncropped at %s = %.4g m, a margin above the highest particle (the box goes to " \
            "%.4g m; --full shows it all)" % (names[up], top, ext[3])
    if len(boxes) > 1:
        sub += "\ndashed: the fluid's blocks of %d ranks (%s)%s" % (
            len(boxes), strategy, "; particles coloured by their rank (left)" if px is not None
            else "")
    fig.suptitle("%s: step %d, t = %.6g s\n%s" % (case, step, time, sub), fontsize=10)
    # where the picture comes from: the run's report.json provenance (else the fields file's)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import provenance
    has = provenance.of_report(report) is not None
    provenance.stamp(fig, reports=[report] if has else [], data_files=[] if has else [fpath])
    # written beside it under a unique name and renamed (coloc's rule for the files it writes:
    # never through a symbolic link, never over anything but a regular file)
    fd, tmp = tempfile.mkstemp(prefix=os.path.basename(png) + ".", suffix=".tmp.png",
                               dir=os.path.dirname(os.path.abspath(png)))
    os.close(fd)
    try:
        provenance.savefig(fig, tmp, dpi=110, bbox_inches="tight", pad_inches=0.1)
        why = png_target_problem(png)
        if why:
            raise OSError(why)
        os.chmod(tmp, 0o644)
        os.replace(tmp, png)
    except BaseException:
        os.unlink(tmp)
        raise
    print("snapshot.py: wrote %s%s" % (png, " (cropped at %s = %.4g m of %.4g m)" % (
        names[up], top, ext[3]) if top < ext[3] else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The standard ParaView pictures of a run, with ParaView's default readers (docs/output.md).

    pvpython --force-offscreen-rendering bench/scripts/render.py OUT_DIR [--time T] [--png-dir D]

Opens OUT_DIR/fields.xmf and OUT_DIR/particles.xmf as File > Open does (OpenDataFile: the Xdmf3
reader) at time T (default: the last output) and writes, to D (default OUT_DIR):

  render_eps.png        the fluid fraction eps on the mid-plane that contains the vertical axis
  render_speed.png      the fluid speed |u| (m/s) on that plane
  render_particles.png  the particles as spheres of their true radius coloured by |v| (m/s), in
                        front of the eps plane
  render_ranks.png      the partition, seen obliquely: every rank's fluid block (report.json
                        partition.boxes: process-grid blocks or tiled boxes) as an outline in the
                        rank's colour, the particles coloured by the rank that owns them (the
                        particle files' `rank`), independent partitions' particle boxes in thin
                        black; the colours are matplotlib's tab20 by rank, as snapshot.png's

The vertical axis is the case's gravity (report.json), else the longest axis. An output without
particles (none inserted yet, or all gone) gives the particle picture of the eps plane alone.
Exit status 0 when the three PNGs are written; 1 with a message when a file has no data (e.g.
particles read as points without cells); 2 with a message when this ParaView draws through an X
server and there is none (no DISPLAY): run it under `xvfb-run -a -s '-screen 0 1280x1024x24 -noreset' pvpython ...` then, instead of
letting ParaView crash.
"""
import argparse
import json
import os
import sys


def needs_x_display():
    """True when ParaView's render windows are X windows (Debian's ParaView) and DISPLAY is unset:
    such a window crashes the process when it is first drawn. A ParaView built for offscreen
    rendering (EGL, OSMesa) draws without one."""
    if os.environ.get("DISPLAY"):
        return False
    try:
        import paraview.modules.vtkRenderingOpenGL2  # noqa: F401  (registers the windows)
        from paraview.modules.vtkRenderingCore import vtkRenderWindow
        window = vtkRenderWindow()  # the factory's choice; opens nothing yet
        return "XOpenGL" in window.GetClassName()
    except Exception:  # an older layout of the modules: X is the common case on Linux
        return sys.platform.startswith("linux")


if needs_x_display():
    print("render.py: no X display (DISPLAY is not set) and this ParaView draws through X: run it "
          "as  xvfb-run -a -s '-screen 0 1280x1024x24 -noreset' pvpython --force-offscreen-rendering bench/scripts/render.py OUT_DIR  "
          "(Debian: apt-get install xvfb), or set DISPLAY", file=sys.stderr)
    sys.exit(2)

from paraview.simple import (Box, ColorBy, CreateView, Delete, GetColorTransferFunction,  # noqa: E402
                             GetScalarBar, OpenDataFile, Render, ResetCamera, SaveScreenshot,
                             Show, Slice, Text)


def vertical_axis(report, length):
    try:
        with open(report) as f:
            g = json.load(f)["config"]["gravity"]
        a = max(range(3), key=lambda d: abs(g[d]))
        if g[a] != 0:
            return a, (1 if g[a] < 0 else -1)
    except (OSError, KeyError, ValueError, TypeError, IndexError):
        pass
    return max(range(3), key=lambda d: length[d]), 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--time", type=float, help="simulated time (s); default: the last output")
    ap.add_argument("--png-dir", help="folder of the PNGs (default: OUT_DIR)")
    ap.add_argument("--size", type=int, nargs=2, default=[900, 900], help="pixels (width height)")
    ap.add_argument("--no-ranks", action="store_true", help="skip render_ranks.png")
    args = ap.parse_args()
    out = os.path.abspath(args.out_dir)
    png_dir = os.path.abspath(args.png_dir or out)
    case = os.path.basename(out)

    fields = OpenDataFile(os.path.join(out, "fields.xmf"))
    times = list(fields.TimestepValues) if hasattr(fields.TimestepValues, "__len__") \
        else [fields.TimestepValues]
    t = args.time if args.time is not None else times[-1]
    # The proxy's UpdatePipeline(t), not simple.UpdatePipeline(): that one drops t = 0.0.
    fields.UpdatePipeline(t)
    info = fields.GetDataInformation()
    if info.GetNumberOfCells() == 0:
        print("render.py: %s has no cells at t = %g" % (fields.FileName, t), file=sys.stderr)
        return 1
    b = info.GetBounds()
    lo, hi = [b[0], b[2], b[4]], [b[1], b[3], b[5]]
    length = [hi[d] - lo[d] for d in range(3)]
    up, sign = vertical_axis(os.path.join(out, "report.json"), length)
    others = [d for d in range(3) if d != up]
    horiz = max(others, key=lambda d: length[d])
    normal = [d for d in others if d != horiz][0]
    centre = [0.5 * (lo[d] + hi[d]) for d in range(3)]
    # The plane through the centres of the middle layer of cells (not on a cell face).
    ext = info.GetExtent()
    ncell = ext[2 * normal + 1] - ext[2 * normal]
    if ncell > 0:
        h = length[normal] / ncell
        centre[normal] = lo[normal] + (ncell // 2 + 0.5) * h

    parts = None
    nparts = 0
    ppath = os.path.join(out, "particles.xmf")
    if os.path.exists(ppath):
        parts = OpenDataFile(ppath)
        parts.UpdatePipeline(t)
        n = parts.GetDataInformation()
        if n.GetNumberOfPoints() > 0 and n.GetNumberOfCells() != n.GetNumberOfPoints():
            print("render.py: %s: %d particles but %d cells (the default reader shows nothing)"
                  % (ppath, n.GetNumberOfPoints(), n.GetNumberOfCells()), file=sys.stderr)
            return 1
        nparts = n.GetNumberOfPoints()

    sl = Slice(Input=fields)
    sl.SliceType = "Plane"
    sl.SliceType.Origin = centre
    sl.SliceType.Normal = [1.0 if d == normal else 0.0 for d in range(3)]

    def view():
        v = CreateView("RenderView")
        v.ViewSize = args.size
        v.ViewTime = t
        v.OrientationAxesVisibility = 1
        v.Background = [1, 1, 1]
        try:
            v.UseColorPaletteForBackground = 0
        except AttributeError:
            pass
        return v

    def camera(v):
        pos = list(centre)
        pos[normal] += 4 * max(length) * (1 if normal != 1 else -1)
        v.CameraPosition = pos
        v.CameraFocalPoint = centre
        v.CameraViewUp = [float(sign) if d == up else 0.0 for d in range(3)]
        ResetCamera(v)

    def title(v, text):
        tx = Text(Text=text)
        d = Show(tx, v)
        d.FontSize = 14
        d.Color = [0, 0, 0]
        d.WindowLocation = "Upper Center"
        provenance_stamp(v)

    # Where the pictures come from (bench/scripts/provenance.py): the run's report.json and the
    # machine drawing them, at the bottom of each.
    report_path = os.path.join(out, "report.json")
    try:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import provenance
        stamp_text = provenance.describe(
            reports=[report_path] if os.path.exists(report_path) else [])[0]
    except Exception as e:  # a picture without its stamp rather than none
        stamp_text = "provenance unavailable: %s" % e

    def provenance_stamp(v):
        tx = Text(Text=stamp_text.replace("|", "/"))
        d = Show(tx, v)
        d.FontSize = 9
        d.Color = [0.4, 0.4, 0.4]
        d.WindowLocation = "Lower Center"

    def flat(d):  # true colours on the plane (no shading)
        d.Ambient = 1.0
        d.Diffuse = 0.0

    def bar(v, array, label, where="Lower Right Corner"):
        lut = GetColorTransferFunction(array)
        sb = GetScalarBar(lut, v)
        sb.WindowLocation = where
        sb.Title = label
        sb.ComponentTitle = ""
        sb.TitleColor = [0, 0, 0]
        sb.LabelColor = [0, 0, 0]
        sb.Visibility = 1
        lut.ApplyPreset({"eps": "Viridis (matplotlib)", "u": "Inferno (matplotlib)"}.get(
            array, "Cool to Warm"), True)
        return lut

    written = []
    stamp = "%s, t = %.6g s" % (case, t)
    # (ParaView's text drops '|', so the speeds are spelled out.)
    for name, array, comp, label in (("eps", "eps", None, "fluid fraction eps (1)"),
                                     ("speed", "u", "Magnitude", "fluid speed (m/s)")):
        v = view()
        d = Show(sl, v)
        flat(d)
        ColorBy(d, ("CELLS", array, comp) if comp else ("CELLS", array))
        d.RescaleTransferFunctionToDataRange(True, False)
        bar(v, array, label)
        title(v, "%s on the mid-plane %s = %.4g m (%s)" % (label, "xyz"[normal], centre[normal],
                                                          stamp))
        camera(v)
        Render(v)
        f = os.path.join(png_dir, "render_%s.png" % name)
        SaveScreenshot(f, v, ImageResolution=args.size)
        written.append(f)
        Delete(v)

    if parts is not None:
        v = view()
        d = Show(sl, v)
        flat(d)
        ColorBy(d, ("CELLS", "eps"))
        d.Opacity = 0.5
        bar(v, "eps", "fluid fraction eps (1)", "Upper Right Corner")
        if nparts > 0:
            pd = show_spheres(parts, v)
            ColorBy(pd, ("POINTS", "v", "Magnitude"))
            pd.RescaleTransferFunctionToDataRange(True, False)
            bar(v, "v", "particle speed (m/s)")
            title(v, "particles coloured by speed, in front of the eps plane (%s, %d particles)"
                  % (stamp, nparts))
        else:  # nothing to colour (no arrays): the plane alone, said so
            title(v, "no particles at this time, the eps plane alone (%s)" % stamp)
        camera(v)
        Render(v)
        f = os.path.join(png_dir, "render_particles.png")
        SaveScreenshot(f, v, ImageResolution=args.size)
        written.append(f)
        Delete(v)
    report = os.path.join(out, "report.json")
    if not args.no_ranks and os.path.exists(report):
        f = os.path.join(png_dir, "render_ranks.png")
        if draw_ranks(report, sl, parts, nparts, t, stamp, args.size, view, title, f):
            written.append(f)
    for f in written:
        print("render.py: wrote %s" % f)
    return 0


# matplotlib's tab20 (snapshot.py and coloc check --draw colour rank r with entry r % 20)
TAB20 = ["#1f77b4", "#aec7e8", "#ff7f0e", "#ffbb78", "#2ca02c", "#98df8a", "#d62728", "#ff9896",
         "#9467bd", "#c5b0d5", "#8c564b", "#c49c94", "#e377c2", "#f7b6d2", "#7f7f7f", "#c7c7c7",
         "#bcbd22", "#dbdb8d", "#17becf", "#9edae5"]


def show_spheres(parts, v):
    """The particles as spheres of their true radius (ParaView's Point Gaussian)."""
    pd = Show(parts, v)
    pd.SetRepresentationType("Point Gaussian")
    pd.ScaleByArray = 1
    pd.SetScaleArray = ["POINTS", "radius"]
    pd.UseScaleFunction = 0
    pd.GaussianRadius = 1.0
    pd.ShaderPreset = "Sphere"
    return pd


def outline(v, lo, hi, colour, width):
    """The edges of the box [lo, hi] in one colour."""
    box = Box(XLength=hi[0] - lo[0], YLength=hi[1] - lo[1], ZLength=hi[2] - lo[2],
              Center=[0.5 * (lo[d] + hi[d]) for d in range(3)])
    d = Show(box, v)
    d.SetRepresentationType("Outline")
    d.AmbientColor = d.DiffuseColor = colour
    d.LineWidth = width


def rgb(hexcolour):
    return [int(hexcolour[i:i + 2], 16) / 255.0 for i in (1, 3, 5)]


def draw_ranks(report, plane, parts, nparts, t, stamp, size, view, title, png):
    """render_ranks.png: the blocks of report.json's partition.boxes as outlines in their rank's
    colour, the particles coloured by their rank. False (with a message) when the report has no
    boxes (a report from before they were written)."""
    with open(report) as f:
        rep = json.load(f)
    part = rep.get("partition", {})
    boxes = part.get("boxes")
    if not boxes:
        print("render.py: %s has no partition.boxes: no render_ranks.png" % report, file=sys.stderr)
        return False
    dom = rep["config"]["domain"]
    origin, length, cells = dom.get("origin", [0, 0, 0]), dom["length"], dom["cells"]
    h = [length[d] / cells[d] for d in range(3)]

    def phys(b):
        lo = [origin[d] + b[d] * h[d] for d in range(3)]
        hi = [origin[d] + b[3 + d] * h[d] for d in range(3)]
        return lo, hi

    up, sign = vertical_axis(report, length)
    v = view()
    for r, b in enumerate(boxes):
        outline(v, *phys(b), rgb(TAB20[r % 20]), 3.0)
    dem = part.get("particle_boxes") or []
    for r, b in enumerate(dem):
        if r < len(boxes) and b == boxes[r]:
            continue
        outline(v, *phys(b), [0, 0, 0], 1.0)
    lut = GetColorTransferFunction("rank")  # one colour a rank, tab20 as snapshot.py's
    lut.InterpretValuesAsCategories = 1
    annotations, colours = [], []
    for r in range(len(boxes)):
        annotations += [str(r), "rank %d" % r]
        colours += rgb(TAB20[r % 20])
    lut.Annotations = annotations
    lut.IndexedColors = colours
    if "rank" in plane.CellData.keys():  # the mid-plane's cells by their owner (fields' /rank)
        pl = Show(plane, v)
        pl.Ambient, pl.Diffuse = 1.0, 0.0
        ColorBy(pl, ("CELLS", "rank"))
        pl.Opacity = 0.35
    if parts is not None and nparts > 0:
        pd = show_spheres(parts, v)
        ColorBy(pd, ("POINTS", "rank"))
        if len(boxes) <= 20:  # a legend of the ranks' colours
            sb = GetScalarBar(lut, v)
            sb.Title = "rank"
            sb.ComponentTitle = ""
            sb.TitleColor = [0, 0, 0]
            sb.LabelColor = [0, 0, 0]
            sb.WindowLocation = "Lower Right Corner"
            sb.Visibility = 1
    what = "%s, %d ranks" % (part.get("strategy", "?"), len(boxes))
    title(v, "the partition (%s): blocks outlined, mid-plane cells and particles coloured by rank (%s)"
          % (what, stamp))
    # An oblique view: the vertical axis up, the camera off every axis.
    centre = [origin[d] + 0.5 * length[d] for d in range(3)]
    others = [d for d in range(3) if d != up]
    pos = list(centre)
    far = 3.0 * max(length)
    pos[others[0]] += 0.8 * far
    pos[others[1]] -= 1.0 * far
    pos[up] += sign * 0.6 * far
    v.CameraPosition = pos
    v.CameraFocalPoint = centre
    v.CameraViewUp = [float(sign) if d == up else 0.0 for d in range(3)]
    ResetCamera(v)
    Render(v)
    SaveScreenshot(png, v, ImageResolution=size)
    Delete(v)
    return True


if __name__ == "__main__":
    sys.exit(main())

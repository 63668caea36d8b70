#!/usr/bin/python3
"""Where a plot's data come from: a stamp in the bottom-right corner of every figure the project
draws, and the full detail in the PNG's text metadata (docs/output.md, "Plots").

    import provenance
    ...                                   # draw; fig.tight_layout() or a constrained layout
    provenance.stamp(fig, reports=[rep1, rep2], data_files=[csv_path])
    provenance.savefig(fig, "out.png", dpi=120)    # fig.savefig with the metadata

The stamp is one or two short grey lines under the figure (the figure grows to make room):
  data:  the runs behind the plot, from their report.json `provenance` (coloc version, git
         commit and whether the tree was dirty, host, CPU model, cores, ranks and oversubscribed,
         the date in UTC; "N runs ... dates A..B" when they differ), or, for a data file without
         provenance (a CSV from before report.json had it), the commit that last changed the file
         and its date (`git log -1 --format='%h %cs' -- FILE`) and "host not recorded";
  drawn: the script, the commit of the source tree it ran from (+dirty), the date (UTC) and the
         machine that drew the figure (which, for a model or any computed plot, is where the
         numbers were computed).
The PNG's "Description" text chunk holds the same in full (one line a run or file) and its
"coloc:provenance" chunk the machine-readable JSON ({"runs": [...], "files": [...], "drawn":
{...}}), read back by `read_png_metadata(path)`.

A CSV written by a script that ran coloc itself may have a sidecar CSV.provenance.json (a JSON
list of the runs' provenance objects, `write_sidecar`): `stamp(data_files=[CSV])` uses it.
Plain Python 3 and matplotlib; no other dependency.
"""
import json
import os
import platform
import socket
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
STAMP_FONTSIZE = 6.0
STAMP_COLOR = "0.45"
METADATA_KEY = "coloc:provenance"


def _git(args, cwd=ROOT):
    try:
        out = subprocess.run(["git"] + args, cwd=cwd, capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def cpu_model():
    """The first "model name" of /proc/cpuinfo (as report.json's provenance.cpu_model), else
    the platform's processor, else "unknown"."""
    fallback = ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, sep, value = line.partition(":")
                key, value = key.strip(), value.strip()
                if not sep or not value:
                    continue
                if key == "model name":
                    return value
                if not fallback and key in ("Processor", "CPU part", "cpu model"):
                    fallback = value
    except OSError:
        pass
    return fallback or platform.processor() or "unknown"


def utc_now():
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def source_tree(root=ROOT):
    """(commit, dirty) of the git checkout at root: the full hash and whether tracked files other
    than PNG images differ from it (re-drawing the committed plots one after the other does not
    make the next one "dirty"); ("unknown", None) outside a git checkout or without git."""
    commit = _git(["rev-parse", "HEAD"], root)
    if not commit:
        return "unknown", None
    status = _git(["status", "--porcelain", "--untracked-files=no", "--", ".", ":(exclude)*.png"],
                  root)
    return commit, (bool(status) if status is not None else None)


def machine(root=ROOT, script=None):
    """This machine's provenance, for scripts that run or compute things themselves: the keys of
    report.json's provenance that make sense outside a coloc run (date UTC, host, cpu_model,
    cores, git_commit, git_dirty of the source tree) and the script, command line, Python and
    matplotlib versions."""
    commit, dirty = source_tree(root)
    p = {"date": utc_now(), "host": socket.gethostname() or "unknown", "cpu_model": cpu_model(),
         "cores": os.cpu_count() or 1, "git_commit": commit, "git_dirty": dirty,
         "python": platform.python_version()}
    try:
        import matplotlib
        p["matplotlib"] = matplotlib.__version__
    except ImportError:
        pass
    script = script or (sys.argv[0] if sys.argv and sys.argv[0] else None)
    if script:
        path = os.path.abspath(script)
        p["script"] = os.path.relpath(path, root) if path.startswith(root + os.sep) else path
    p["command_line"] = " ".join(_quote(a) for a in sys.argv) if sys.argv else ""
    return p


def _quote(a):
    import shlex
    return shlex.quote(a)


def of_report(rep):
    """The provenance object of a report (a dict or a path to report.json), with coloc_version
    filled in from the report's top level; None when the report has none (an older report)."""
    if isinstance(rep, (str, os.PathLike)):
        try:
            with open(rep) as f:
                rep = json.load(f)
        except (OSError, ValueError):
            return None
    if not isinstance(rep, dict):
        return None
    if "provenance" in rep:
        p = dict(rep["provenance"] or {})
        if "coloc_version" not in p and "coloc_version" in rep:
            p["coloc_version"] = rep["coloc_version"]
        return p
    if "date" in rep and "host" in rep:  # already a provenance object (a sidecar's entry)
        return dict(rep)
    return None


def sidecar_path(data_file):
    return str(data_file) + ".provenance.json"


def write_sidecar(data_file, reports):
    """DATA_FILE.provenance.json: the provenance objects of the runs behind a data file (a JSON
    list), so that a later re-plot from the file alone still stamps where they came from."""
    provs = [p for p in (of_report(r) for r in reports) if p is not None]
    with open(sidecar_path(data_file), "w") as f:
        json.dump(provs, f, indent=1)
        f.write("\n")
    return provs


def file_origin(path):
    """Where a data file without provenance comes from: the commit that last changed it in git,
    that commit's date, and whether the file differs from it now."""
    path = os.path.abspath(path)
    d = os.path.dirname(path)
    info = {"file": os.path.basename(path)}
    top = _git(["rev-parse", "--show-toplevel"], d)
    if top:
        info["file"] = os.path.relpath(path, top)
    log = _git(["log", "-1", "--format=%h %cs", "--", path], d)
    if log:
        info["commit"], info["commit_date"] = log.split(" ", 1)
        info["modified"] = bool(_git(["status", "--porcelain", "--", path], d))
    else:
        info["commit"] = None  # not in git (or no git)
        try:
            info["mtime"] = time.strftime("%Y-%m-%d", time.gmtime(os.path.getmtime(path)))
        except OSError:
            pass
    return info


def _short(commit, dirty=None):
    if not commit or commit == "unknown":
        return "commit unknown"
    return commit[:7] + ("+dirty" if dirty else "")


def _day(date):
    return (date or "?")[:10]


def _minute(date):
    """'2026-12-04T19:11:27Z' -> '2026-12-04 19:11 UTC'."""
    if not date or len(date) < 16:
        return date or "date unknown"
    return date[:10] + " " + date[11:16] + " UTC"


def _span(values):
    vals = sorted(set(v for v in values if v is not None))
    if not vals:
        return None
    return str(vals[0]) if len(vals) == 1 else "%s..%s" % (vals[0], vals[-1])


def _one_of_each(values, what):
    vals = list(dict.fromkeys(v for v in values if v))
    if len(vals) <= 2:
        return ", ".join(vals)
    return "%d %s" % (len(vals), what)


def runs_line(provs):
    """One line on the runs behind a plot."""
    n = len(provs)
    ver = _one_of_each(["coloc " + str(p["coloc_version"]) for p in provs
                        if p.get("coloc_version")], "versions")
    commits = _one_of_each([_short(p.get("git_commit"), p.get("git_dirty")) for p in provs],
                           "commits")
    hosts = list(dict.fromkeys(p.get("host", "?") for p in provs))
    cpus = list(dict.fromkeys(p.get("cpu_model", "?") for p in provs))
    cores = _span([p.get("cores") for p in provs])
    if len(hosts) == 1:
        where = "host %s (%s, %s cores)" % (hosts[0], "; ".join(cpus), cores)
    else:
        where = "%d hosts (%s)" % (len(hosts), _one_of_each(hosts, "hosts"))
    ranks = _span([p.get("ranks") for p in provs])
    over = sum(1 for p in provs if p.get("oversubscribed"))
    sim = sum(1 for p in provs if p.get("simulated"))
    rk = "%s rank%s" % (ranks, "" if ranks == "1" else "s")
    if over:
        rk += ", oversubscribed" if over == n else ", %d of %d oversubscribed" % (over, n)
    else:
        rk += ", not oversubscribed"
    if sim:
        rk += ", SIMULATED (SMPI)" if sim == n else ", %d simulated" % sim
    head = "1 run" if n == 1 else "%d runs" % n
    days = _span([_day(p.get("date")) for p in provs])
    when = _minute(provs[0].get("date")) if n == 1 else (days if ".." not in days
                                                         else "dates " + days)
    return "data: %s of %s @ %s, %s, %s, %s" % (head, ver or "coloc", commits, where, rk, when)


def files_line(infos):
    parts = []
    for i in infos:
        name = os.path.basename(i["file"])
        if i.get("commit"):
            parts.append("%s (commit %s, %s%s)" % (name, i["commit"], i["commit_date"],
                                                  ", modified since" if i.get("modified") else ""))
        else:
            parts.append("%s (not in git%s)" % (name, ", " + i["mtime"] if i.get("mtime") else ""))
    return "data: %s; host not recorded" % "; ".join(parts)


def drawn_line(m, extra=""):
    script = os.path.basename(m.get("script", "")) or "python"
    s = "drawn by %s @ %s on %s (%s, %s cores), %s" % (
        script, _short(m.get("git_commit"), m.get("git_dirty")), m.get("host"),
        m.get("cpu_model"), m.get("cores"), _minute(m.get("date")))
    return (extra + "; " + s) if extra else s


def describe(reports=(), data_files=(), extra="", drawn=None):
    """(stamp text, full text, JSON-able dict) for the runs (report dicts or report.json paths)
    and the data files (paths) behind a plot; extra: a short note put before "drawn by"."""
    provs = [p for p in (of_report(r) for r in reports) if p is not None]
    missing = sum(1 for r in reports if of_report(r) is None)
    infos = []
    for f in data_files:
        side = sidecar_path(f)
        if os.path.exists(side):
            try:
                with open(side) as fh:
                    provs += [p for p in (of_report(x) for x in json.load(fh)) if p is not None]
                continue
            except (OSError, ValueError):
                pass
        infos.append(file_origin(f))
    drawn = drawn or machine()
    lines = []
    if provs:
        lines.append(runs_line(provs))
    if infos:
        lines.append(files_line(infos))
    if missing:
        lines.append("data: %d run%s without provenance in report.json (host not recorded)" %
                     (missing, "" if missing == 1 else "s"))
    lines.append(drawn_line(drawn, extra))
    # Two lines at most in the stamp: the data lines joined; the full text keeps them all.
    short = [" | ".join(lines[:-1])] if len(lines) > 1 else []
    short.append(lines[-1])
    full = ["coloc plot provenance"]
    for p in provs:
        full.append("run: " + ", ".join("%s=%s" % (k, v) for k, v in p.items()))
    for i in infos:
        full.append("file: " + ", ".join("%s=%s" % (k, v) for k, v in i.items()))
    if missing:
        full.append("runs without provenance: %d" % missing)
    full.append("drawn: " + ", ".join("%s=%s" % (k, v) for k, v in drawn.items()))
    if extra:
        full.append("note: " + extra)
    data = {"runs": provs, "files": infos, "runs_without_provenance": missing, "drawn": drawn,
            "note": extra}
    return "\n".join(short), "\n".join(full), data


def _latin1(s):
    return s.encode("latin-1", "replace").decode("latin-1")


def stamp(fig, reports=(), data_files=(), extra="", drawn=None, fontsize=STAMP_FONTSIZE):
    """Write the provenance stamp in the bottom-right corner of fig, below everything else (the
    figure grows by the stamp's height and the axes keep their size), and remember the full
    detail for savefig(). Call it after the layout (tight_layout) and before saving. Returns the
    stamp text."""
    text, full, data = describe(reports, data_files, extra, drawn)
    nlines = text.count("\n") + 1
    dh = (nlines * fontsize * 1.3 + 4.0) / 72.0  # inches
    w, h = fig.get_size_inches()
    engine = fig.get_layout_engine()
    # Keep every artist where it is in inches from the top: shift up by dh what is placed in
    # figure fractions (axes, colorbars, figure texts, figure legends).
    old_texts = [(t, t.get_position()) for t in fig.texts]
    if getattr(fig, "_suptitle", None) is not None and fig._suptitle not in fig.texts:
        old_texts.append((fig._suptitle, fig._suptitle.get_position()))
    fig.set_size_inches(w, h + dh, forward=True)
    f = h / (h + dh)
    b = dh / (h + dh)
    if engine is not None and hasattr(engine, "set") and "rect" in engine.get():
        engine.set(rect=(0, b, 1, f))  # constrained or tight layout: lay out above the stamp
    else:
        for ax in fig.axes:
            pos = ax.get_position(original=True)
            ax.set_position([pos.x0, b + pos.y0 * f, pos.width, pos.height * f], which="both")
    for t, (x, y) in old_texts:
        if t.get_transform() == fig.transSubfigure or t.get_transform() == fig.transFigure:
            t.set_position((x, b + y * f))
    pad = 2.0 / 72.0 / w
    fig.text(1 - pad, 2.0 / 72.0 / (h + dh), text, ha="right", va="bottom", fontsize=fontsize,
             color=STAMP_COLOR, family="sans-serif", gid="coloc-provenance-stamp")
    fig._coloc_provenance = {"Description": _latin1(full),
                             METADATA_KEY: json.dumps(data, ensure_ascii=True, sort_keys=True)}
    return text


def metadata(fig):
    """The PNG text metadata of a stamped figure ({} when it has no stamp)."""
    return dict(getattr(fig, "_coloc_provenance", {}))


def savefig(fig, path, **kw):
    """fig.savefig(path, **kw) with the stamp's full provenance in the PNG's text metadata
    ("Description" and "coloc:provenance"; formats without free text keys get the Description
    only where they support it)."""
    md = dict(kw.pop("metadata", {}) or {})
    prov = metadata(fig)
    ext = os.path.splitext(str(path))[1].lower()
    if ext == ".png":
        md.update(prov)
    elif ext in (".pdf", ".svg") and prov:
        md.setdefault("Subject" if ext == ".pdf" else "Description", prov["Description"])
    fig.savefig(path, metadata=md or None, **kw)


def read_png_metadata(path):
    """The text chunks (tEXt, zTXt, iTXt) of a PNG file, as a dict; standard library only."""
    import struct
    import zlib
    out = {}
    with open(path, "rb") as f:
        if f.read(8) != b"\x89PNG\r\n\x1a\n":
            raise ValueError("%s is not a PNG" % path)
        while True:
            head = f.read(8)
            if len(head) < 8:
                break
            n, kind = struct.unpack(">I4s", head)
            body = f.read(n)
            f.read(4)  # CRC
            if kind == b"tEXt":
                k, _, v = body.partition(b"\0")
                out[k.decode("latin-1")] = v.decode("latin-1")
            elif kind == b"zTXt":
                k, _, v = body.partition(b"\0")
                out[k.decode("latin-1")] = zlib.decompress(v[1:]).decode("latin-1")
            elif kind == b"iTXt":
                k, _, rest = body.partition(b"\0")
                comp, _method, rest = rest[0], rest[1], rest[2:]
                _lang, _, rest = rest.partition(b"\0")
                _tk, _, v = rest.partition(b"\0")
                out[k.decode("latin-1")] = (zlib.decompress(v) if comp else v).decode("utf-8")
            elif kind == b"IEND":
                break
    return out


if __name__ == "__main__":
    # provenance.py [REPORT.json ...]: this machine's provenance, or the stamp of those runs.
    if len(sys.argv) > 1:
        print(describe(reports=sys.argv[1:])[0])
    else:
        print(json.dumps(machine(), indent=1))

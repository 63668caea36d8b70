"""Read coloc's run folders from Python (docs/output.md, "Reading runs from Python").

    import coloc
    run = coloc.read_run("out/case1-np2")
    run.report["run"]["wall_s"]          # report.json as a dict
    run["timers.dem_force.max"]          # ... or by a key path with dots
    run.series["time"], run.series["p0_x"]   # series.csv: one numpy array per column
    run.steps                            # the steps with fields output (fields_NNNNNN.h5)
    f = run.fields()                     # the last output: {"p": array[nz, ny, nx], "u": ...}
    f.attrs["time"], f.step              # the file's attributes
    p = run.particles(step=20)           # {"id": ..., "x": array[N, 3], "v": ..., ...}
    run.log                              # log.txt

The HDF5 files are read with h5py (numpy and h5py: Debian's python3-numpy, python3-h5py);
report.json and series.csv need numpy only. Installed with coloc (`cmake --install`) in
PREFIX/share/coloc/python: `PYTHONPATH=PREFIX/share/coloc/python python3 -c "import coloc"`
(the installed scripts find it themselves).
"""
import csv
import glob
import json
import os
import re
import shutil

__all__ = ["Run", "Output", "read_run", "read_report", "read_series", "output_steps",
           "report_value", "find_coloc"]


class Output(dict):
    """The datasets of one output file (name -> numpy array), with the file's attributes in
    `attrs` (time, step, origin, spacing, cells, count, ...) and each dataset's units in
    `units`."""

    def __init__(self, path, arrays, attrs, units):
        super().__init__(arrays)
        self.path = path
        self.attrs = attrs
        self.units = units

    @property
    def step(self):
        return int(self.attrs.get("step", -1))

    @property
    def time(self):
        return float(self.attrs.get("time", float("nan")))


def read_report(path):
    """report.json as a dict."""
    with open(path) as f:
        return json.load(f)


def report_value(report, key, default=KeyError):
    """The value of a report at a key path with dots ("timers.dem_force.max", "fluid.drag_force.2"):
    the default when it has none (KeyError when no default is given)."""
    v = report
    for part in key.split("."):
        if isinstance(v, dict) and part in v:
            v = v[part]
        elif isinstance(v, list) and part.isdigit() and int(part) < len(v):
            v = v[int(part)]
        else:
            if default is KeyError:
                raise KeyError("%s: no such key in the report (at '%s')" % (key, part))
            return default
    return v


def read_series(path):
    """series.csv as {column: numpy array of float64}; the empty cells of the diagnostics
    columns (computed on some steps only) are NaN."""
    import numpy as np
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    out = {}
    for i, name in enumerate(header):
        col = [(r[i] if i < len(r) else "") for r in body]
        out[name] = np.array([float(v) if v.strip() != "" else np.nan for v in col],
                             dtype=float)
    return out


def output_steps(folder, series="fields"):
    """The steps of FOLDER/SERIES_NNNNNN.h5 (series "fields" or "particles"), sorted."""
    steps = []
    for f in glob.glob(os.path.join(folder, series + "_*.h5")):
        m = re.search(r"_(\d+)\.h5$", os.path.basename(f))
        if m:
            steps.append(int(m.group(1)))
    return sorted(steps)


class Run:
    """One run folder of `coloc run` (its --out): report.json, series.csv, log.txt, and the
    HDF5 output of output.dir (the same folder unless the case moved it)."""

    def __init__(self, folder, data_dir=None):
        self.folder = folder
        path = os.path.join(folder, "report.json")
        if not os.path.isfile(path):
            raise FileNotFoundError("%s: no report.json (not the --out folder of a coloc run?)"
                                    % folder)
        self.report = read_report(path)
        self.data_dir = data_dir or self._data_dir()
        self._series = None

    def _data_dir(self):
        d = report_value(self.report, "config.output.dir", "") or ""
        if not d:
            return self.folder
        for cand in (d, os.path.join(self.folder, d)):
            if os.path.isdir(cand):
                return cand
        return d if os.path.isabs(d) else os.path.join(self.folder, d)

    def __getitem__(self, key):
        """A report value by its key path with dots: run["run.wall_s"]."""
        return report_value(self.report, key)

    def get(self, key, default=None):
        return report_value(self.report, key, default)

    @property
    def provenance(self):
        return self.report.get("provenance", {})

    @property
    def status(self):
        return self.report.get("status")

    @property
    def series(self):
        """series.csv: {column: numpy array} (read once)."""
        if self._series is None:
            path = os.path.join(self.folder, "series.csv")
            self._series = read_series(path) if os.path.exists(path) else {}
        return self._series

    @property
    def log(self):
        path = os.path.join(self.folder, "log.txt")
        if not os.path.exists(path):
            return ""
        with open(path, errors="replace") as f:
            return f.read()

    @property
    def steps(self):
        """The steps with fields output."""
        return output_steps(self.data_dir, "fields")

    @property
    def particle_steps(self):
        return output_steps(self.data_dir, "particles")

    def _read(self, series, step):
        steps = output_steps(self.data_dir, series)
        if not steps:
            raise FileNotFoundError("%s: no %s_*.h5 (the case writes them with "
                                    "output.interval_steps > 0)" % (self.data_dir, series))
        if step is None:
            step = steps[-1]
        if step not in steps:
            raise KeyError("no %s output at step %d in %s; the steps with output: %s"
                           % (series, step, self.data_dir, ", ".join(map(str, steps))))
        import h5py
        path = os.path.join(self.data_dir, "%s_%06d.h5" % (series, step))
        arrays, attrs, units = {}, {}, {}
        with h5py.File(path, "r") as f:
            for k, v in f.attrs.items():
                attrs[k] = v.decode() if isinstance(v, bytes) else v
            for name, ds in f.items():
                arrays[name] = ds[...]
                u = ds.attrs.get("units")
                if u is not None:
                    units[name] = u.decode() if isinstance(u, bytes) else str(u)
        attrs.setdefault("step", step)
        return Output(path, arrays, attrs, units)

    def fields(self, step=None):
        """The cell fields of an output step (default: the last): scalar fields [nz, ny, nx],
        vectors [nz, ny, nx, 3], x fastest (docs/output.md)."""
        return self._read("fields", step)

    def particles(self, step=None):
        """The particles of an output step (default: the last): id [N], x [N, 3], v, omega,
        radius, material, fluid_force, rank (and temperature with particles.heat)."""
        return self._read("particles", step)

    def __repr__(self):
        r = self.report.get("run", {})
        return "<coloc run %s: %s, %s ranks, %s steps, status %s>" % (
            self.folder, self.report.get("case"), report_value(self.report, "mpi.ranks", "?"),
            r.get("steps", "?"), self.status)


def read_run(folder, data_dir=None):
    """The run in FOLDER (a `coloc run --out` folder): a Run (report, series, fields,
    particles, log). `data_dir`: where its HDF5 output is, when output.dir moved it elsewhere
    and the report's relative path does not find it."""
    return Run(folder, data_dir)


def find_coloc():
    """The coloc binary a script should run: the one installed beside these files
    (PREFIX/bin/coloc for PREFIX/share/coloc/python), else the source tree's build/coloc, else
    `coloc` on PATH; None when there is none."""
    here = os.path.dirname(os.path.abspath(__file__))
    share = os.path.dirname(os.path.dirname(here))  # PREFIX/share/coloc or the source's bench
    for cand in (os.path.join(os.path.dirname(os.path.dirname(share)), "bin", "coloc"),
                 os.path.join(os.path.dirname(share), "build", "coloc")):
        if os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    return shutil.which("coloc")

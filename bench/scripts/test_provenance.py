#!/usr/bin/python3
"""Unit test of bench/scripts/provenance.py: the stamp on the project's plots (docs/output.md,
"Plots"). A figure stamped from a tiny fake report.json says its commit, host and date in the
stamp, under the axes, and holds the full provenance in the PNG's text metadata; a CSV without
provenance is stamped "host not recorded"; strategies.py --plot-only and snapshot.py (on a
tiny fake output, when h5py is there) stamp their PNGs. No MPI, no coloc run. CTest:
provenance_unit (label unit)."""
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import provenance  # noqa: E402

FAILS = []


def check(what, ok):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


PROV = {"date": "2031-05-06T07:08:09Z", "host": "fakehost-17", "cpu_model": "Fake CPU 9000",
        "cores": 48, "ranks": 96, "nodes": 2, "ranks_per_node_max": 48, "simulated": False,
        "oversubscribed": False, "cores_used": 96, "coloc_version": "9.8.7",
        "git_commit": "0123456789abcdef0123456789abcdef01234567", "git_dirty": True,
        "compiler": "GNU 99.1.0", "compiler_flags": "-O3", "build_type": "Release",
        "mpi_library": "Fake MPI 1.0", "command_line": "coloc run fake.json --out x",
        "hypre_version": "2.26.0", "hdf5_version": "1.10.8"}


def stamped_figure(tmp):
    rep = {"coloc_version": "9.8.7", "provenance": PROV, "run": {"steps": 1}}
    path = os.path.join(tmp, "report.json")
    with open(path, "w") as f:
        json.dump(rep, f)
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("x label")
    fig.tight_layout()
    ax_bottom = ax.get_position().y0 * fig.get_size_inches()[1]
    text = provenance.stamp(fig, reports=[path])
    png = os.path.join(tmp, "fake.png")
    provenance.savefig(fig, png, dpi=80)
    check("stamp has the commit (short)", "0123456+dirty" in text)
    check("stamp has the host and CPU", "fakehost-17" in text and "Fake CPU 9000" in text)
    check("stamp has the run's date (UTC)", "2031-05-06 07:08 UTC" in text)
    check("stamp has ranks and oversubscription", "96 ranks, not oversubscribed" in text)
    check("stamp has the coloc version", "coloc 9.8.7" in text)
    check("stamp has who drew it", "drawn by" in text)
    check("stamp is at most two lines", text.count("\n") <= 1)
    # the figure grew and the axes moved up by the stamp's height: nothing drawn over the axes
    stamps = [t for t in fig.texts if t.get_gid() == "coloc-provenance-stamp"]
    check("one stamp text on the figure", len(stamps) == 1)
    if stamps:
        fig.canvas.draw()
        bb = stamps[0].get_window_extent()
        axbb = ax.get_tightbbox(fig.canvas.get_renderer())
        check("stamp below the axes and their labels (%.1f <= %.1f px)" % (bb.y1, axbb.y0),
              bb.y1 <= axbb.y0 + 0.5)
        check("stamp in the right-hand corner", bb.x1 >= 0.95 * fig.bbox.width)
        check("axes keep their height from the figure's bottom plus the stamp",
              ax.get_position().y0 * fig.get_size_inches()[1] > ax_bottom)
    md = provenance.read_png_metadata(png)
    check("PNG has a Description", "Description" in md)
    desc = md.get("Description", "")
    for key in ("fakehost-17", "Fake CPU 9000", "GNU 99.1.0", "Fake MPI 1.0", "hdf5_version=1.10.8",
                "command_line=coloc run fake.json --out x", PROV["git_commit"]):
        check("Description holds %s" % key, key in desc)
    try:
        data = json.loads(md.get(provenance.METADATA_KEY, "null"))
        check("coloc:provenance JSON holds the run's provenance",
              data["runs"][0]["git_commit"] == PROV["git_commit"] and
              data["runs"][0]["hypre_version"] == "2.26.0" and "host" in data["drawn"])
    except (ValueError, KeyError, IndexError, TypeError) as e:
        check("coloc:provenance JSON readable (%s)" % e, False)
    plt.close(fig)


def several_runs():
    a = dict(PROV, date="2031-05-06T07:08:09Z", ranks=1)
    b = dict(PROV, date="2031-05-09T07:08:09Z", ranks=4, oversubscribed=True)
    text = provenance.describe(reports=[{"provenance": a}, {"provenance": b}])[0]
    check("several runs: count, rank range, dates range",
          "2 runs" in text and "1..4 ranks" in text and "1 of 2 oversubscribed" in text
          and "2031-05-06..2031-05-09" in text)


def csv_without_provenance(tmp):
    """A data file in git without provenance: the commit that last changed it, host not
    recorded."""
    env = dict(os.environ, GIT_AUTHOR_NAME="t", GIT_AUTHOR_EMAIL="t@t", GIT_COMMITTER_NAME="t",
               GIT_COMMITTER_EMAIL="t@t", GIT_COMMITTER_DATE="2030-01-02T03:04:05Z",
               GIT_AUTHOR_DATE="2030-01-02T03:04:05Z")
    repo = os.path.join(tmp, "repo")
    os.makedirs(repo)
    path = os.path.join(repo, "data.csv")
    with open(path, "w") as f:
        f.write("a,b\n1,2\n")
    for cmd in (["git", "init", "-q"], ["git", "add", "data.csv"],
                ["git", "commit", "-q", "-m", "data"]):
        subprocess.run(cmd, cwd=repo, env=env, check=True, capture_output=True)
    head = subprocess.run(["git", "rev-parse", "--short=7", "HEAD"], cwd=repo, env=env,
                          capture_output=True, text=True).stdout.strip()
    text = provenance.describe(data_files=[path])[0]
    check("CSV stamp: commit %s and its date, host not recorded" % head,
          head in text and "2030-01-02" in text and "host not recorded" in text)
    return repo


def strategies_plot_only(tmp):
    out = os.path.join(tmp, "strat")
    os.makedirs(out)
    keys = ["strategy", "ranks", "repeat", "oversubscribed", "steps", "fluid_dims", "particle_dims",
            "busy_max_per_step", "busy_avg_per_step", "imbalance", "wall_per_step",
            "inter_remote_bytes_per_step", "inter_remote_messages_per_step",
            "inter_local_bytes_per_step", "frac_inter_physics", "frac_inter_remote",
            "modelled_imbalance"]
    with open(os.path.join(out, "strategies.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for s in ("uniform", "balanced"):
            for n in (2, 4):
                w.writerow([s, n, 0, int(n > 2), 10, "2x1x1", "2x1x1", 0.01, 0.008, 1.2, 0.02,
                            1000.0 * n, 4, 0, 0.01, 0.005, ""])
    # the runs' provenance beside the CSV (what strategies.py writes when it runs them)
    with open(os.path.join(out, "strategies.csv.provenance.json"), "w") as f:
        json.dump([PROV, dict(PROV, ranks=4)], f)
    r = subprocess.run([sys.executable, os.path.join(HERE, "strategies.py"), "fake.json",
                        "--plot-only", "--cores", "2", "--out", out], capture_output=True, text=True)
    check("strategies.py --plot-only runs (%s)" % r.stderr.strip()[-200:], r.returncode == 0)
    for png in ("imbalance.png", "busy_max.png", "inter_physics.png", "inter_physics_bytes.png"):
        p = os.path.join(out, png)
        md = provenance.read_png_metadata(p) if os.path.exists(p) else {}
        check("strategies %s stamped from the sidecar's runs" % png,
              "fakehost-17" in md.get("Description", "") and "ranks=4" in md.get("Description", ""))


def snapshot(tmp):
    try:
        import h5py
        import numpy as np
    except ImportError:
        print("skip snapshot.py (no h5py)")
        return
    out = os.path.join(tmp, "run")
    os.makedirs(out)
    with h5py.File(os.path.join(out, "fields_000010.h5"), "w") as f:
        f.attrs["origin"] = [0.0, 0.0, 0.0]
        f.attrs["spacing"] = [0.01, 0.01, 0.01]
        f.attrs["cells"] = [4, 4, 8]
        f.attrs["time"] = 0.1
        f["eps"] = np.ones((8, 4, 4))
        f["u"] = np.zeros((8, 4, 4, 3))
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump({"coloc_version": "9.8.7", "provenance": PROV,
                   "config": {"gravity": [0, 0, -9.81]}}, f)
    r = subprocess.run([sys.executable, os.path.join(HERE, "snapshot.py"), out],
                       capture_output=True, text=True)
    check("snapshot.py runs (%s)" % r.stderr.strip()[-200:], r.returncode == 0)
    p = os.path.join(out, "snapshot.png")
    md = provenance.read_png_metadata(p) if os.path.exists(p) else {}
    check("snapshot.png stamped from its report.json",
          "fakehost-17" in md.get("Description", "") and PROV["git_commit"] in
          md.get("Description", ""))


def main():
    m = provenance.machine()
    check("machine(): host, CPU, cores, commit, date",
          all(m.get(k) for k in ("host", "cpu_model", "cores", "git_commit", "date")))
    with tempfile.TemporaryDirectory() as tmp:
        stamped_figure(tmp)
        several_runs()
        csv_without_provenance(tmp)
        strategies_plot_only(tmp)
        snapshot(tmp)
    if FAILS:
        print("provenance: %d check(s) failed" % len(FAILS))
        return 1
    print("provenance: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

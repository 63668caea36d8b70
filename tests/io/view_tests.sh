#!/usr/bin/env bash
# view_tests.sh TEST COLOC MPIEXEC PYTHON CASE WORKDIR [PVPYTHON] — what a user sees of a run
# (docs/output.md), on the tiny fluidised bed tests/robustness/cases/bed.json.
#
#   diagnostics  the bed diagnostics of series.csv and report.json on 1 and 2 ranks agree to
#                1e-9 (relative), are filled on the output steps only, and equal what numpy
#                computes from the particle output (bed height: exactly the 95th percentile,
#                nearest rank; mean/max speed); series.csv follows output.series_particle_ids
#   snapshot     snapshot.png is written at the end of a run with fields (a PNG of a sensible
#                size), not with output.snapshot=false or without periodic output; the script
#                fails with a message on a folder without output
#   snapshot_steps  `coloc snapshot OUT --step N` of a step without output: exit 2, a message
#                listing the steps with output, no traceback; of a step with output: drawn. The
#                default crop above the bed keeps every block face the plane cuts in view (a
#                low bed under the face of a 1 x 1 x 2 process grid: cropped above that face)
#   paraview     with ParaView's default reader (OpenDataFile) particles.xmf gives N points AND N
#                cells and fields.xmf nx*ny*nz cells at every output time, with their arrays
#   render       render.py writes its four PNGs (offscreen; through xvfb-run when there is no
#                X display); on an output without particles too, without a warning; the
#                partition picture holds the outline colour of every rank of the 2-rank run
#   nodisplay    render.py without DISPLAY either renders (a ParaView that draws offscreen) or
#                exits 2 saying that there is no X display; never killed by a signal
# paraview and render exit 77 (SKIPPED) where there is no pvpython; render also where there is
# neither an X display nor xvfb-run (Debian's ParaView renders through X).
set -u
test=$1 coloc=$2 mpiexec=$3 py=$4 case=$5 work=$6
pvpython=${7:-}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
scripts="$here/../../bench/scripts"
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
run() {
  local np=$1 out=$2
  shift 2
  timeout 120 "$mpiexec" -n "$np" --bind-to none "$coloc" run "$case" --out "$out" --quiet "$@" \
    > "$out.log" 2>&1
  local rc=$?
  [[ $rc -ne 0 ]] && { cat "$out.log"; fail "coloc run exited $rc: $*"; }
  return 0
}

case $test in
diagnostics)
  for np in 1 2; do
    run $np "$work/r$np" --set output.interval_steps=5 --set output.snapshot=false \
      --set "output.series_particle_ids=[3,17]"
  done
  "$py" - "$work/r1" "$work/r2" <<'EOF' || fail "diagnostics"
import csv, json, math, sys
import h5py, numpy as np
a, b = sys.argv[1:3]
cols = ["bed_height", "mean_speed", "max_speed", "contacts_per_particle", "dp_bed_pa",
        "dp_box_pa", "dp_bed_excess_pa", "dp_box_excess_pa", "bed_weight_pa",
        "solid_fraction_max", "solid_fraction_bed_mean"]
def rows(d):
    with open(d + "/series.csv") as f:
        return list(csv.DictReader(f))
ra, rb = rows(a), rows(b)
hdr = list(ra[0].keys())
assert "p3_x" in hdr and "p17_fz" in hdr and "p0_x" not in hdr, hdr
for c in cols:
    assert c in hdr, c
assert len(ra) == len(rb) == 10
def close(x, y, tol=1e-9):
    return abs(x - y) <= tol * max(abs(x), abs(y), 1e-300)
for x, y in zip(ra, rb):
    step = int(x["step"])
    filled = step % 5 == 0 or step == 10
    for c in cols:
        assert (x[c] != "") == filled and (y[c] != "") == filled, (step, c, x[c], y[c])
        if filled:
            assert close(float(x[c]), float(y[c])), (step, c, x[c], y[c])
    for c in ("p3_x", "p17_vz"):
        assert close(float(x[c]), float(y[c]), 1e-9), (step, c)
# against the particle output of step 10 (z up from 0, 400 particles)
with h5py.File(a + "/particles_000010.h5") as f:
    z, v, ids, x = f["x"][:, 2], f["v"][...], f["id"][...], f["x"][...]
last = ra[-1]
k = math.ceil(0.95 * len(z))
assert float(last["bed_height"]) == np.sort(z)[k - 1], (last["bed_height"], np.sort(z)[k - 1])
s = np.linalg.norm(v, axis=1)
assert close(float(last["mean_speed"]), s.mean(), 1e-12)
assert float(last["max_speed"]) == s.max()
i3 = int(np.where(ids == 3)[0][0])
assert float(last["p3_x"]) == x[i3, 0]
ja, jb = (json.load(open(d + "/report.json"))["bed"] for d in (a, b))
for key, va in ja.items():
    vb = jb[key]
    if isinstance(va, list):
        assert all(close(p, q) for p, q in zip(va, vb)), key
    elif isinstance(va, float):
        assert close(va, vb), (key, va, vb)
    else:
        assert va == vb, (key, va, vb)
assert ja["bed_height_m"] == float(last["bed_height"])
assert abs(sum(ja["solid_fraction_profile"]) * 0.01 * 0.01 * 0.0025 -
           400 * 4 / 3 * math.pi * 0.0005 ** 3) < 1e-12, "solid fraction profile: volume"
# the pressure drop over the box less its hydrostatic part is of the order of the bed's weight
assert 0.2 < ja["dp_box_excess_pa"] / ja["bed_weight_pa"] < 2, ja
print("PASS: diagnostics on 1 and 2 ranks agree and match the particle output")
EOF
  ;;
snapshot)
  run 1 "$work/on" --set output.interval_steps=5
  [[ -s "$work/on/snapshot.png" ]] || fail "no snapshot.png"
  "$py" - "$work/on/snapshot.png" <<'EOF' || fail "snapshot.png is not a sensible PNG"
import sys
import matplotlib.image as mi
a = mi.imread(sys.argv[1])
assert a.shape[0] > 300 and a.shape[1] > 300, a.shape
assert a[..., :3].std() > 0.05, "a blank picture"
print("PASS: snapshot.png", a.shape)
EOF
  # the bed fills the lower 40 % of the tiny column: the picture is cropped above it, and --full
  # draws the whole box, taller
  "$py" "$scripts/snapshot.py" "$work/on" --png "$work/crop.png" > "$work/crop.log" 2>&1 ||
    { cat "$work/crop.log"; fail "snapshot.py by hand"; }
  grep -q "(cropped at z = " "$work/crop.log" || { cat "$work/crop.log"; fail "no crop above the bed"; }
  "$py" "$scripts/snapshot.py" "$work/on" --png "$work/full.png" --full > "$work/full.log" 2>&1 ||
    { cat "$work/full.log"; fail "snapshot.py --full"; }
  grep -q "cropped" "$work/full.log" && fail "--full cropped"
  "$py" - "$work/crop.png" "$work/full.png" <<'EOF' || fail "--full is not the taller picture"
import sys
import matplotlib.image as mi
c, f = mi.imread(sys.argv[1]), mi.imread(sys.argv[2])
print("cropped", c.shape, "full", f.shape)
assert f.shape[0] / f.shape[1] > c.shape[0] / c.shape[1], (c.shape, f.shape)
EOF
  run 1 "$work/off" --set output.interval_steps=5 --set output.snapshot=false
  [[ -e "$work/off/snapshot.png" ]] && fail "snapshot.png written with output.snapshot=false"
  run 1 "$work/none"
  [[ -e "$work/none/snapshot.png" ]] && fail "snapshot.png written without periodic output"
  mkdir -p "$work/empty"
  out=$("$py" "$scripts/snapshot.py" "$work/empty" 2>&1) && fail "snapshot.py passed on no output"
  grep -q "no fields_" <<<"$out" || fail "snapshot.py message: $out"
  echo "PASS: snapshot"
  ;;
snapshot_steps)
  # a low bed (150 particles below z = 6 mm) on two blocks cut at z = 20 mm (cell 8 of 16)
  run 2 "$work/s" --set run.steps=10 --set output.interval_steps=5 \
    --set 'partition.dims=[1,1,2]' --set particles.sources.0.count=150 \
    --set 'particles.sources.0.hi=[0.01,0.01,0.006]'
  "$coloc" snapshot "$work/s" --step 7 > "$work/bad.log" 2>&1
  rc=$?
  cat "$work/bad.log"
  [[ $rc -eq 2 ]] || fail "coloc snapshot --step 7 (no output there) exited $rc, expected 2"
  grep -q "no output at step 7 in '$work/s' (no fields_000007.h5); the steps with output: 0, 5, 10" \
    "$work/bad.log" || fail "no message listing the steps"
  grep -q "Traceback" "$work/bad.log" && fail "a Python traceback"
  "$coloc" snapshot "$work/s" --step 5 --png "$work/s5.png" > "$work/s5.log" 2>&1 ||
    { cat "$work/s5.log"; fail "coloc snapshot --step 5"; }
  [[ -s $work/s5.png ]] || fail "no s5.png"
  cat "$work/s5.log"
  "$py" - "$work/s5.log" "$work/s/report.json" <<'EOF' || fail "the crop hides a block face"
import json, re, sys
text, d = open(sys.argv[1]).read(), json.load(open(sys.argv[2]))
m = re.search(r"cropped at z = ([0-9.e+-]+) m of ([0-9.e+-]+) m", text)
assert m, "not cropped (the bed is low: it should be)"
top, box = float(m.group(1)), float(m.group(2))
dz = d["config"]["domain"]["length"][2] / d["config"]["domain"]["cells"][2]
faces = sorted({b[k] * dz for b in d["partition"]["boxes"] for k in (2, 5)} - {0.0, box})
print("crop at", top, "faces", faces)
assert faces == [0.02], faces
assert top >= faces[-1] + 2 * dz - 1e-12 and top < box, (top, faces)
EOF
  echo "PASS: snapshot_steps"
  ;;
paraview | render | nodisplay)
  if [[ -z "$pvpython" || ! -x "$pvpython" ]]; then
    echo "SKIPPED: no pvpython (install ParaView, e.g. apt-get install paraview, and re-run cmake)"
    exit 77
  fi
  if [[ $test == nodisplay ]]; then
    run 1 "$work/r" --set output.interval_steps=5 --set output.snapshot=false --set run.steps=5
    timeout 300 env -u DISPLAY "$pvpython" --force-offscreen-rendering "$scripts/render.py" \
      "$work/r" > "$work/render.log" 2>&1
    rc=$?
    cat "$work/render.log"
    [[ $rc -lt 124 ]] || fail "render.py without a display ended with $rc (killed by a signal?)"
    if [[ $rc -ne 0 ]]; then
      [[ $rc -eq 2 ]] || fail "render.py without a display exited $rc, expected 0 or 2"
      grep -q "render.py: no X display" "$work/render.log" || fail "no message about the display"
    fi
    echo "PASS: nodisplay (exit $rc)"
    exit 0
  fi
  if [[ $test == render && -z "${DISPLAY:-}" ]]; then
    if ! command -v xvfb-run > /dev/null; then
      echo "SKIPPED: no X display and no xvfb-run (apt-get install xvfb) for pvpython to render"
      exit 77
    fi
    # One X server for every picture of the test, which does not reset when its last client
    # leaves: ParaView opens the display more than once, and a connection made while the server
    # resets fails ("bad X server connection", SIGABRT; one run in three here without -noreset).
    exec xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" bash "${BASH_SOURCE[0]}" "$test" "$coloc" "$mpiexec" "$py" "$case" "$work" \
      "$pvpython"
  fi
  run 2 "$work/r" --set output.interval_steps=5 --set output.snapshot=false
  if [[ $test == paraview ]]; then
    cat > "$work/probe.py" <<'EOF'
import sys
from paraview.simple import OpenDataFile
d = sys.argv[1]
p = OpenDataFile(d + "/particles.xmf")
f = OpenDataFile(d + "/fields.xmf")
assert type(p).__name__.startswith("Xdmf3Reader"), type(p).__name__
for t in p.TimestepValues:
    p.UpdatePipeline(t)
    i = p.GetDataInformation()
    assert i.GetNumberOfPoints() == 400 and i.GetNumberOfCells() == 400, \
        (t, i.GetNumberOfPoints(), i.GetNumberOfCells())
    f.UpdatePipeline(t)
    assert f.GetDataInformation().GetNumberOfCells() == 4 * 4 * 16, t
assert len(p.TimestepValues) == 3, p.TimestepValues
for a in ("v", "radius", "id", "rank"):
    assert a in p.PointData.keys(), a
for a in ("eps", "u", "p", "K", "rank"):
    assert a in f.CellData.keys(), a
print("PASS: the default reader gives 400 vertex cells and 256 field cells at",
      list(p.TimestepValues))
EOF
    timeout 200 "$pvpython" "$work/probe.py" "$work/r" > "$work/probe.log" 2>&1
    rc=$?
    grep -v "^$" "$work/probe.log" | tail -5
    [[ $rc -eq 0 ]] || fail "ParaView probe exited $rc"
    exit 0
  fi
  timeout 300 "$pvpython" --force-offscreen-rendering "$scripts/render.py" "$work/r" \
    > "$work/render.log" 2>&1
  rc=$?
  tail -5 "$work/render.log"
  [[ $rc -eq 0 ]] || fail "render.py exited $rc"
  for f in render_eps render_speed render_particles render_ranks; do
    [[ -s "$work/r/$f.png" ]] || fail "no $f.png"
  done
  # render_ranks.png: each rank's block outline in its tab20 colour (flat lines: exact pixels)
  "$py" - "$work/r/render_ranks.png" <<'EOF2' || fail "render_ranks.png lacks a rank's colour"
import sys
import matplotlib.image as mpimg
import numpy as np
img = (mpimg.imread(sys.argv[1])[..., :3] * 255).round().astype(int)
for r, c in enumerate(["#1f77b4", "#aec7e8"]):  # ranks 0 and 1
    rgb = np.array([int(c[i:i + 2], 16) for i in (1, 3, 5)])
    n = int((np.abs(img - rgb).max(axis=-1) <= 2).sum())
    print("rank %d colour %s: %d pixels" % (r, c, n))
    assert n >= 50, (r, c, n)
EOF2
  # an output without particles: the three pictures, no warning
  run 1 "$work/empty" --set output.interval_steps=5 --set output.snapshot=false \
    --set run.steps=5 --set 'particles.sources=[]'
  timeout 300 "$pvpython" --force-offscreen-rendering "$scripts/render.py" \
    "$work/empty" > "$work/render_empty.log" 2>&1
  rc=$?
  tail -5 "$work/render_empty.log"
  [[ $rc -eq 0 ]] || fail "render.py on an output without particles exited $rc"
  grep -qi "warn" "$work/render_empty.log" && fail "render.py warned on an output without particles"
  [[ -s "$work/empty/render_particles.png" ]] || fail "no render_particles.png without particles"
  echo "PASS: render.py"
  ;;
*) fail "unknown test $test" ;;
esac

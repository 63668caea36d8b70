#!/usr/bin/env bash
# install_tests.sh CMAKE BUILD MPIEXEC PYTHON CASE WORKDIR — the installed coloc (issue 28):
# `cmake --install BUILD --prefix WORKDIR/prefix`, then the installed binary
#   - the prefix holds the scripts, the cases and the docs (share/coloc/...);
#   - moved elsewhere (mv PREFIX MOVED), runs CASE on 2 ranks with fields output and leaves
#     OUT/snapshot.png, drawn (its log says) by MOVED/share/coloc/scripts/snapshot.py: neither the
#     source tree's nor the install prefix's;
#   - `coloc snapshot OUT --png FILE --full` draws again without mpirun (no MPI at all), and a bad
#     command line exits 2;
#   - every script of bench/scripts but the tests is installed (render.py, scaling.py, collect.py,
#     ...), with the Python module coloc and the Slurm scripts; `import coloc` from
#     PREFIX/share/coloc/python reads the run; the installed collect.py makes its CSV row; the
#     installed scaling.py runs the installed binary; `coloc --version` names the installed data.
set -u
cmake=$1 build=$2 mpiexec=$3 py=$4 case=$5 work=$6
rm -rf "$work" && mkdir -p "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
prefix=$(realpath "$work")/prefix
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log" 2>&1 ||
  { cat "$work/install.log"; fail "cmake --install"; }
[[ -x $prefix/bin/coloc ]] || fail "no $prefix/bin/coloc"
for f in scripts/snapshot.py scripts/provenance.py cases/bed-small.json docs/output.md \
         docs/cluster.md python/coloc/__init__.py slurm/coloc.sbatch slurm/paper.sh; do
  [[ -s $prefix/share/coloc/$f ]] || fail "not installed: share/coloc/$f"
done
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
for f in "$src"/bench/scripts/*.py "$src"/bench/scripts/*.sh; do
  name=$(basename "$f")
  [[ $name == test_* ]] && continue
  [[ -x $prefix/share/coloc/scripts/$name ]] || fail "not installed (executable): share/coloc/scripts/$name"
done
ls "$prefix"/share/coloc/scripts/test_* > /dev/null 2>&1 && fail "a script's test installed"
# a prefix that moves keeps working: the binary finds its data relative to itself
moved=$(realpath "$work")/moved
mv "$prefix" "$moved" || fail "mv $prefix $moved"
coloc=$moved/bin/coloc
share=$moved/share/coloc

out=$work/out
timeout 120 "$mpiexec" -n 2 --bind-to none "$coloc" run "$case" --out "$out" --quiet \
  --set output.interval_steps=5 > "$work/run.log" 2>&1 ||
  { cat "$work/run.log"; fail "the installed coloc run exited $?"; }
[[ -s $out/snapshot.png ]] || { cat "$work/run.log"; fail "no snapshot.png"; }
grep -qxF "coloc: drawing snapshot.png with $share/scripts/snapshot.py" "$out/log.txt" ||
  { cat "$out/log.txt"; fail "the snapshot was not drawn by the installed script"; }
grep -q "^snapshot.py: wrote " "$out/log.txt" || fail "the script's output is not in log.txt"

# post-processing after the job: no mpirun
timeout 120 "$coloc" snapshot "$out" --png "$work/full.png" --full > "$work/snap.log" 2>&1 ||
  { cat "$work/snap.log"; fail "coloc snapshot exited $?"; }
[[ -s $work/full.png ]] || fail "coloc snapshot wrote no full.png"
grep -q "^snapshot.py: wrote .*full.png" "$work/snap.log" || { cat "$work/snap.log"; fail "no output"; }

# the run's data from Python, with the installed module and scripts only
PYTHONPATH=$share/python "$py" - "$out" "$share" <<'EOF' || fail "import coloc from the installed prefix"
import sys
import coloc
out, share = sys.argv[1], sys.argv[2]
assert coloc.__file__.startswith(share + "/python/coloc/"), coloc.__file__
run = coloc.read_run(out)
assert run.status == "ok" and run["mpi.ranks"] == 2, run
assert run.steps and run.fields()["eps"].ndim == 3 and len(run.particles()["id"]) > 0
assert len(run.series["time"]) >= run["run.steps"], (len(run.series["time"]), run["run.steps"])
assert coloc.find_coloc() == share[: -len("/share/coloc")] + "/bin/coloc", coloc.find_coloc()
print("import coloc:", run)
EOF
"$py" "$share/scripts/collect.py" "$out" --out "$work/c.csv" > "$work/collect.log" 2>&1 ||
  { cat "$work/collect.log"; fail "the installed collect.py"; }
[[ $(wc -l < "$work/c.csv") -eq 2 ]] || fail "collect.py: not one row"
"$py" "$share/scripts/scaling.py" --help > "$work/scaling.log" 2>&1 || { cat "$work/scaling.log"; fail "scaling.py --help"; }
tr -s ' \n' ' ' < "$work/scaling.log" | grep -qF "(default: the installed one" || fail "scaling.py --help"
"$coloc" --version > "$work/version.log" 2>&1 || { cat "$work/version.log"; fail "coloc --version"; }
cat "$work/version.log"
grep -qx "  data: *$share (scripts, cases)" "$work/version.log" || fail "--version does not name $share"

"$coloc" snapshot > "$work/usage.log" 2>&1
rc=$?
[[ $rc -eq 2 ]] || { cat "$work/usage.log"; fail "coloc snapshot without OUT_DIR exited $rc, not 2"; }
echo "PASS: installed to $prefix, moved to $moved; snapshot.png drawn by $share/scripts/snapshot.py"

#!/usr/bin/env bash
# scaling_default_out.sh PYTHON COLOC SOURCE WORKDIR — bench/scripts/scaling.py without --out
# writes under the folder it is started in (out/<case>-scaling/, as `coloc run` writes out/<case>/),
# never into the source tree's bench/results/ (issue 29). One tiny run: the bed case, 1 rank, 1
# fluid step.
set -u
py=$1 coloc=$2 src=$3 work=$4
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work" && mkdir -p "$work" || exit 1
cp "$src/tests/robustness/cases/bed.json" "$work/scaling-probe.json" || exit 1
[[ -e $src/bench/results/scaling-probe ]] && fail "bench/results/scaling-probe exists before the run"
cd "$work" || exit 1
timeout 120 "$py" "$src/bench/scripts/scaling.py" scaling-probe.json --ranks 1 --modes fluid \
  --coloc "$coloc" --set run.steps=1 > scaling.log 2>&1
rc=$?
cat scaling.log
[[ $rc -eq 0 ]] || fail "scaling.py exited $rc"
if [[ -e $src/bench/results/scaling-probe ]]; then
  rm -rf "$src/bench/results/scaling-probe"
  fail "scaling.py wrote into the source tree's bench/results/"
fi
[[ -s $work/out/scaling-probe-scaling/scaling.csv ]] || fail "no out/scaling-probe-scaling/scaling.csv"
grep -qF "scaling: wrote $work/out/scaling-probe-scaling/scaling.csv" scaling.log ||
  fail "scaling.py does not say where it wrote"
echo "PASS: scaling.py writes under $work/out/"

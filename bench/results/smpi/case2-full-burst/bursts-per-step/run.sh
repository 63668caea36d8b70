#!/bin/bash
# Case 2 at full size, uniform, 3 coupled steps at each rank count, every burst SMPI charges put
# in a time series of the simulated clock (hist4.c, preloaded after smpi_run.py's own library):
# tP.ts (1 ms slots: bursts and charge by size class) and tP-report.json. analyse4.py turns them
# into table.md (docs/smpi.md, "Where a step's time goes at 56-280 ranks").
#   bench/results/smpi/case2-full-burst/bursts-per-step/run.sh [OUT]    (PS="56 112" to choose)
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here}
cd "$here/../../../../.."  # the repository root
tmp=$(mktemp -d)
gcc -O2 -shared -fPIC -o "$tmp/libhist4.so" "$here/hist4.c" -ldl -lsimgrid || exit 1
for P in ${PS:-56 112 168 280}; do
  echo "== $P $(date -u +%T) $(cat /proc/loadavg)"
  HIST_OUT=$out/t$P.ts LD_PRELOAD=$tmp/libhist4.so /usr/bin/python3 bench/scripts/smpi_run.py \
    --ranks "$P" --platform paper -- run bench/cases/case2.json --quiet --overwrite \
    --set run.steps=3 --set run.timer_sync=true --out "$tmp/t$P" > "$tmp/t$P.log" 2>&1
  tail -1 "$tmp/t$P.log"
  cp "$tmp/t$P/report.json" "$out/t$P-report.json"
done
rm -rf "$tmp"

#!/bin/bash
# case 2 at full size on the simulated paper cluster: one strategy at a time, the load before each
cd "$(dirname "$0")/../../../.."  # the repository root
for s in ${STRATS:-uniform tiled balanced independent}; do
  echo "== $s $(date -u +%H:%M:%S) $(cat /proc/loadavg)"
  python3 bench/scripts/smpi_scaling.py bench/cases/case2.json --ranks ${RANKS:-28,56,112,168,252,280} \
    --strategies $s --steps 1 --set run.timer_sync=true \
    --model ${CAL:-out/c2-np1/report.json} --out ${OUT:-out/c2-smpi} --resume
  echo "== $s done $(date -u +%H:%M:%S) $(cat /proc/loadavg)"
done

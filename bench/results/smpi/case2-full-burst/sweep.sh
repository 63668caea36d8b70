#!/bin/bash
# case 2 at full size on the simulated paper cluster with the charge of an empty burst subtracted
# (smpi_run.py's default since 9ba4246) and hypre built with Debian's flags: the points of
# ../case2-full again, beside the same model calibration; one strategy at a time, the load logged.
cd "$(dirname "$0")/../../../.."  # the repository root
CAL=${CAL:-bench/results/smpi/case2-full/calibration-np1-report.json}
run() {  # strategy ranks
  echo "== $1 $2 $(date -u +%H:%M:%S) $(cat /proc/loadavg)"
  python3 bench/scripts/smpi_scaling.py bench/cases/case2.json --ranks "$2" --strategies "$1" \
    --steps 1 --set run.timer_sync=true --model "$CAL" --out "${OUT:-out/c2-smpi-burst}" --resume
  echo "== $1 $2 done $(date -u +%H:%M:%S) $(cat /proc/loadavg)"
}
for point in ${POINTS:-uniform:28,56,112,168,252,280 uniform:1024 tiled:28,56,112,168,252,280}; do
  run "${point%%:*}" "${point#*:}"
done

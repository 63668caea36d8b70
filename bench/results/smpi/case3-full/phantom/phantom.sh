#!/bin/bash
# What SMPI charges a rank for an MPI call with no work around it (docs/smpi.md, "Case 3 at full
# size"): toy.c calls MPI_Sendrecv ITERS times around a loop of N additions; the simulated time
# with the bursts charged minus the same run with smpi/simulate-computation:no, divided by the
# calls, is the computation SMPI charges a call. Needs cmake/setup-smpi.sh (smpicc, smpirun).
#   bench/results/smpi/case3-full/phantom/phantom.sh [RANKS...]     (default 2 8 28 112 280)
set -e
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../../../.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
smpicc -O2 "$here/toy.c" -o "$tmp/toy" 2>/dev/null
echo "ranks  charged us/call  network only us/call  phantom us/call"
for P in ${@:-2 8 28 112 280}; do
  t=()
  for comp in yes no; do
    t+=($(/usr/bin/python3 "$root/bench/scripts/smpi_run.py" --ranks "$P" --platform paper \
          --exe "$tmp/toy" --cfg smpi/simulate-computation:$comp -- 2000 0 |
          sed -n 's/.* \([0-9.]*\) us\/iter.*/\1/p'))
  done
  echo "$P ${t[0]} ${t[1]}" | awk '{printf "%5d  %15.3f  %20.3f  %15.3f\n", $1, $2, $3, $2 - $3}'
done

#!/bin/bash
# The planner's figures for the tiled strategy (docs/plan.md, "Tiled layouts"): imbalance, halo
# and inter-physics bytes of uniform, balanced and tiled on the clustered case and on case 3 at
# 4, 8, 64, 256 and 1024 ranks. One process, no MPI ranks; about 20 s here.
#   bench/results/tiled/run.sh [BUILD_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
build=${1:-$root/build}
cd "$root"
for c in clustered case3; do
  "$build/coloc" plan "bench/cases/$c.json" --ranks 4,8,64,256,1024 \
    --strategy uniform --strategy balanced --strategy tiled --out "$here/plan-$c" \
    > "$here/plan-$c.log"
  # plan.csv (one row per rank) is left out: plan.json holds the same per-rank arrays
  rm -f "$here/plan-$c/plan.csv"
done
python3 "$here/table.py" "$here/plan-clustered/plan.json" "$here/plan-case3/plan.json" \
  > "$here/table.md"
cat "$here/table.md"

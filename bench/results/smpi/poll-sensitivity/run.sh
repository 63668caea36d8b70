#!/bin/bash
# The simulated pressure set-up against the simulated cost of one MPI_Iprobe (issue 51;
# docs/smpi.md, "hypre's set-up against the cost of a poll"): case2-small, one step, 8-64
# simulated ranks on the paper platform, smpi/iprobe as smpi_run.py measures it (a real
# Open MPI MPI_Iprobe, ~3.4e-8 s here) and set to 1e-9, 1e-7 and 1e-6 s.
# usage: run.sh ROOT OUT    (ROOT: a tree with build/ and build-smpi/); then table.py OUT
set -eu
ROOT=$1 OUT=$2
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
point() {  # RANKS IPROBE(measured | seconds)
  local cfg=() name="np$1-measured"
  if [[ $2 != measured ]]; then cfg=(--cfg "smpi/iprobe:$2"); name="np$1-ip$2"; fi
  /usr/bin/python3 "$ROOT/bench/scripts/smpi_run.py" --ranks "$1" --platform paper \
    --smpi-build "$ROOT/build-smpi" --real-build "$ROOT/build" "${cfg[@]}" -- \
    run "$ROOT/bench/cases/case2-small.json" --set run.steps=1 --set run.timer_sync=true \
    --quiet --overwrite --out "$OUT/$name" > "$OUT/$name.log" 2>&1
  tail -1 "$OUT/$name.log"
}
for np in 8 16 32 64; do point $np measured; done
point 32 1e-9
point 32 1e-6
point 64 1e-7
point 64 1e-6
/usr/bin/python3 "$(dirname "$0")/table.py" "$OUT"

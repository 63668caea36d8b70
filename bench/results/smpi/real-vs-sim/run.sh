#!/bin/bash
# Real against simulated at 1 and 2 ranks (issue 51): the same case run by the Open MPI build
# (real ranks, one a core, polling) and by the SMPI build on the paper platform (smpi_run.py with
# its calibration), alternating, ROUNDS rounds; compare.py tabulates the pressure set-up (a
# set-up), the pressure solve and the whole step (a step).
# usage: run.sh ROOT OUT ROUNDS    (ROOT: a tree with build/ and build-smpi/)
set -eu
ROOT=$1 OUT=$2 ROUNDS=$3
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_mpi_yield_when_idle=0
export OMPI_MCA_btl_vader_single_copy_mechanism=none
c2=$ROOT/bench/cases/case2-small.json c3=$ROOT/bench/cases/case3-small.json
dense=$(/usr/bin/python3 "$ROOT/bench/scripts/dense_bed.py" "$c3")
for r in $(seq 1 "$ROUNDS"); do
  for np in 1 2; do
    for c in case2-small case3-dense; do
      if [[ $c == case2-small ]]; then args=("$c2" --set run.steps=20); else args=("$c3" --set "$dense" --set run.steps=4); fi
      args+=(--set run.timer_sync=true --set output.snapshot=false --quiet --overwrite)
      mpirun -n "$np" --bind-to core "$ROOT/build/coloc" run "${args[@]}" --out "$OUT/$c-np$np-real-$r" > /dev/null
      /usr/bin/python3 "$ROOT/bench/scripts/smpi_run.py" --ranks "$np" --platform paper \
        --smpi-build "$ROOT/build-smpi" --real-build "$ROOT/build" -- run "${args[@]}" \
        --out "$OUT/$c-np$np-sim-$r" > "$OUT/$c-np$np-sim-$r.log" 2>&1
      echo "round $r: $c on $np ranks done"
    done
  done
done
/usr/bin/python3 "$(dirname "$0")/compare.py" "$OUT"

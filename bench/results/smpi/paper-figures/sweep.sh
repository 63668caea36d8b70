#!/bin/bash
# The paper's two scaling figures on the simulated paper cluster (issue 51; docs/smpi.md, "The
# paper's figures, executed"): case 2 at full size (2 M cells, 1 M particles, DummyDEM) at 28-252
# simulated ranks and case 3 at full size in contact (10 M particles) at 28-280 and 1024, the
# four strategies, with the model calibrated on a real 1-rank run of the same build; the same
# points again at 28 and 280 ranks (repeatability); the set-up reuse's simulated gain (case 2 at
# 252 and case 3 at 280 with fluid.pressure.setup_interval = 1). Every smpi_scaling.py call
# keeps the points already in its --out (--resume): a stopped sweep goes on where it stopped,
# and the last calls, over points already simulated, only write the CSVs and figures.
# usage: sweep.sh ROOT OUT    ROOT: a source tree whose build/ (Open MPI) and build-smpi/ hold
#                             the binaries; OUT: where the points go
set -eu
ROOT=$1 OUT=$2
S=$ROOT/bench/scripts
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
common=(--platform paper --smpi-build "$ROOT/build-smpi" --real-build "$ROOT/build"
        --coloc "$ROOT/build/coloc" --resume)
c2=$ROOT/bench/cases/case2.json c3=$ROOT/bench/cases/case3.json
dense=$(/usr/bin/python3 "$S/dense_bed.py" "$c3")
all=uniform,balanced,tiled,independent
log() { echo "$(date -u +%H:%M:%S) $*" | tee -a "$OUT/sweep.log"; }
c2run() { /usr/bin/python3 "$S/smpi_scaling.py" "$c2" "${common[@]}" --steps 3 --model "$OUT/case2-np1/report.json" "$@" >> "$OUT/sweep.log" 2>&1; }
c3run() { /usr/bin/python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --steps 1 --model "$OUT/case3-np1/report.json" "$@" >> "$OUT/sweep.log" 2>&1; }
# the model's calibration: a real 1-rank run of each case, this build
if [[ ! -f $OUT/case2-np1/report.json ]]; then
  log "calibration case 2"
  "$ROOT/build/coloc" run "$c2" --set run.steps=3 --quiet --overwrite --out "$OUT/case2-np1"
fi
if [[ ! -f $OUT/case3-np1/report.json ]]; then
  log "calibration case 3"
  "$ROOT/build/coloc" run "$c3" --set "$dense" --set run.steps=1 --quiet --overwrite \
    --out "$OUT/case3-np1"
fi
log "case 2 uniform, 28-252"
c2run --ranks 28,56,112,168,252 --strategies uniform --out "$OUT/case2"
log "case 3, 28-280, four strategies"
c3run --ranks 28,56,112,168,252,280 --strategies $all --out "$OUT/case3"
log "repeatability: case 3 uniform and tiled at 28 and 280, case 2 uniform at 28 and 252, again"
c3run --ranks 28,280 --strategies uniform,tiled --out "$OUT/case3-again"
c2run --ranks 28,252 --strategies uniform --out "$OUT/case2-again"
log "case 3 at 1024, uniform and tiled"
c3run --ranks 280,1024 --strategies uniform,tiled --out "$OUT/case3-1024"
log "the set-up reuse's gain: setup_interval = 1"
c2run --ranks 252 --strategies uniform --set fluid.pressure.setup_interval=1 --out "$OUT/case2-interval1"
c3run --ranks 280 --strategies uniform --set fluid.pressure.setup_interval=1 --out "$OUT/case3-interval1"
log "case 2, the other strategies"
c2run --ranks 28,56,112,168,252 --strategies $all --out "$OUT/case2"
log "done"

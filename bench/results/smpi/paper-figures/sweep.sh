#!/bin/bash
# The paper's two scaling figures on the simulated paper cluster (issue 51; docs/smpi.md, "The
# paper's figures, executed"): case 2 at full size (2 M cells, 1 M particles, DummyDEM) at 28-252
# simulated ranks and case 3 at full size in contact (10 M particles) at 28-280 and 1024, the
# four strategies, with the model calibrated on a real 1-rank run of the same build; then the
# same points again at 28 and 280 ranks (repeatability).
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
dense=$(python3 "$S/dense_bed.py" "$c3")
log() { echo "$(date -u +%H:%M:%S) $*" | tee -a "$OUT/sweep.log"; }
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
log "case 2, 28-252"
python3 "$S/smpi_scaling.py" "$c2" "${common[@]}" --ranks 28,56,112,168,252 \
  --strategies uniform,balanced,tiled,independent --steps 3 \
  --model "$OUT/case2-np1/report.json" --out "$OUT/case2" >> "$OUT/sweep.log" 2>&1
log "case 3, 28-280"
python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --ranks 28,56,112,168,252,280 \
  --strategies uniform,balanced,tiled,independent --steps 1 \
  --model "$OUT/case3-np1/report.json" --out "$OUT/case3" >> "$OUT/sweep.log" 2>&1
log "repeatability: case 3 uniform and tiled at 28 and 280, case 2 uniform at 28 and 252, again"
python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --ranks 28,280 \
  --strategies uniform,tiled --steps 1 --out "$OUT/case3-again" >> "$OUT/sweep.log" 2>&1
python3 "$S/smpi_scaling.py" "$c2" "${common[@]}" --ranks 28,252 \
  --strategies uniform --steps 3 --out "$OUT/case2-again" >> "$OUT/sweep.log" 2>&1
log "case 3 at 1024, uniform and tiled"
python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --ranks 280,1024 \
  --strategies uniform,tiled --steps 1 \
  --model "$OUT/case3-np1/report.json" --out "$OUT/case3-1024" >> "$OUT/sweep.log" 2>&1
log "done"

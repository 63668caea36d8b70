#!/bin/bash
# case 3 points in order of value (session 2026-12-08)
set -u
ROOT=/work/sweep OUT=/work/sweep-out
S=$ROOT/bench/scripts
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
common=(--platform paper --smpi-build "$ROOT/build-smpi" --real-build "$ROOT/build"
        --coloc "$ROOT/build/coloc" --resume)
c3=$ROOT/bench/cases/case3.json
log() { echo "$(date -u +%H:%M:%S) $*" | tee -a "$OUT/sweep.log"; }
run() { # ranks strategies
  log "case 3 $2 at $1"
  /usr/bin/python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --ranks "$1" \
    --strategies "$2" --steps 1 --model "$OUT/case3-np1/report.json" --out "$OUT/case3" >> "$OUT/sweep.log" 2>&1
}
run 28,280 tiled
run 28,280 balanced
run 28,280 uniform
run 28,56,112,168,280 tiled
run 28,56,112,168,280 balanced
run 28,56,112,168,252,280 tiled,balanced
run 28,56,112,168,252,280 uniform
log "again"
/usr/bin/python3 "$S/smpi_scaling.py" "$c3" --dense-bed "${common[@]}" --ranks 28,280 \
  --strategies tiled --steps 1 --out "$OUT/case3-again" >> "$OUT/sweep.log" 2>&1
run 28,56,112,168,252,280 uniform,balanced,tiled,independent
log done

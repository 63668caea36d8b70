#!/bin/bash
# A/B of two coloc binaries on the fluid's per-cell loops (issue 30): case2-small (DummyDEM, 110 x
# 22 x 22 cells, inlet, outlet, walls) for STEPS steps, one rank pinned to core 1, the binaries
# alternating, ROUNDS rounds; prints the fluid timers that hold the rewritten loops (busy s over
# the run: fluid_pressure_assemble = matrix + rhs + hypre's set-up; fluid_cell_fields holds the
# pressure gradient; the rates at the end of a step are in no phase) and the wall time a step.
# usage: [CASE=fluid-channel] ab.sh ROUNDS STEPS OUTDIR LABEL=BINARY LABEL=BINARY ...
# (CASE: a case of bench/cases, default case2-small; fluid-channel is the 625k-cell channel of the
# icoFoam comparison)
set -u
ROUNDS=$1 STEPS=$2 OUT=$3
shift 3
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
CASE=${CASE:-case2-small}
for r in $(seq 1 "$ROUNDS"); do
  for lb in "$@"; do
    label=${lb%%=*} bin=${lb#*=}
    taskset -c 1 "$bin" run "$ROOT/bench/cases/$CASE.json" --quiet --overwrite \
      --out "$OUT/$CASE-$label-$r" --set run.steps="$STEPS" >/dev/null 2>&1
    python3 - "$OUT/$CASE-$label-$r/report.json" "$CASE $label" "$r" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); t = r["timers"]
b = lambda k: t[k]["busy_avg"] if k in t else 0.0
fluid = sum(b(k) for k in t if k.startswith("fluid_"))
print(f"{sys.argv[2]} round {sys.argv[3]}: pressure_assemble {b('fluid_pressure_assemble'):.4f} "
      f"cell_fields {b('fluid_cell_fields'):.4f} pressure_solve {b('fluid_pressure_solve'):.4f} "
      f"fluid {fluid:.4f} s/step {r['run']['wall_s'] / r['run']['steps']:.5f}")
PY
  done
done

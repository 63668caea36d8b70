#!/bin/bash
# The pressure set-up reuse (issue 51), real runs: a case on NP ranks for STEPS coupled steps,
# variants alternating round after round; one CSV row a run (stdout): the wall time a step, the
# pressure phases a step (busy = thread CPU, rank average: fluid_pressure_assemble = matrix and
# right-hand side; fluid_pressure_setup = hypre's set-ups, 0 in builds before the split, which
# book them in the assembly), PCG iterations a step and the set-ups of the run.
# usage: ab.sh CASE NP STEPS ROUNDS OUTDIR LABEL=BINARY[@KEY=VALUE,...] ...
#   CASE: case2-small, or case3-dense (case3-small with its bed in contact, dense_bed.py)
#   e.g. ab.sh case2-small 1 40 3 out/ab before=/work/main/build/coloc \
#          i1=build/coloc@fluid.pressure.setup_interval=1 i20=build/coloc
set -u
CASE=$1 NP=$2 STEPS=$3 ROUNDS=$4 OUT=$5
shift 5
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
file=$ROOT/bench/cases/$CASE.json
extra=()
if [[ $CASE == case3-dense ]]; then
  file=$ROOT/bench/cases/case3-small.json
  extra=(--set "$(python3 "$ROOT/bench/scripts/dense_bed.py" "$file")")
fi
echo "case,ranks,label,round,step_s,assemble_s,setup_s,solve_s,iterations,setups,steps"
for r in $(seq 1 "$ROUNDS"); do
  for lb in "$@"; do
    label=${lb%%=*} rest=${lb#*=}
    bin=${rest%%@*} sets=()
    if [[ $rest == *@* ]]; then
      IFS=, read -ra kv <<< "${rest#*@}"
      for x in "${kv[@]}"; do sets+=(--set "$x"); done
    fi
    dir=$OUT/$CASE-np$NP-$label-$r
    mpirun -n "$NP" --bind-to none "$bin" run "$file" "${extra[@]}" "${sets[@]}" --quiet \
      --overwrite --out "$dir" --set run.steps="$STEPS" --set output.snapshot=false >/dev/null 2>&1 ||
      { echo "ab.sh: $label round $r failed" >&2; continue; }
    python3 - "$dir/report.json" "$CASE,$NP,$label,$r" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); t = r["timers"]; n = r["run"]["steps"]
b = lambda k: t[k]["busy_avg"] / n if k in t else 0.0
p = r.get("pressure", {})
print(f"{sys.argv[2]},{r['run']['wall_s'] / n:.5f},{b('fluid_pressure_assemble'):.5f},"
      f"{b('fluid_pressure_setup'):.5f},{b('fluid_pressure_solve'):.5f},"
      f"{p.get('iterations_avg', 0):.3f},{p.get('setups', 0)},{n}")
PY
  done
done

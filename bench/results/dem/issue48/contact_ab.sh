#!/bin/bash
# A/B of coloc binaries on case3-small in contact (issue 48): STEPS coupled steps (10 DEM sub-steps
# each) restarted from a settled checkpoint that bench/scripts/contact_bench.py writes
# (WORK/settled.h5), on RANKS ranks (1: pinned to core 1; more: mpirun --bind-to none), the
# binaries alternating, ROUNDS rounds; prints the DEM timers (busy seconds a step, the mean over
# the ranks: report.json timers.*.busy_avg / steps) and the wall time a step.
# usage: [RANKS=1] [STEPS=20] [START=200] [CASE=bench/cases/case3-small.json] \
#        contact_ab.sh ROUNDS SETTLED.h5 \
#          OUTDIR LABEL=BINARY ... [-- coloc run arguments, e.g. --set key=value]
set -u
ROUNDS=$1 SETTLED=$2 OUT=$3
shift 3
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
RANKS=${RANKS:-1} STEPS=${STEPS:-20} CASE=${CASE:-$ROOT/bench/cases/case3-small.json}
bins=()
while (($#)) && [[ $1 != -- ]]; do bins+=("$1"); shift; done
(($#)) && shift
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
  OMPI_MCA_btl_vader_single_copy_mechanism=none
if ((RANKS == 1)); then launch=(taskset -c 1); else launch=(mpirun -n "$RANKS" --bind-to none); fi
START=${START:-200}  # the checkpoint's step (contact_bench.py --settle-steps)
for r in $(seq 1 "$ROUNDS"); do
  for lb in "${bins[@]}"; do
    label=${lb%%=*} bin=${lb#*=}
    load=$(cut -d' ' -f1 /proc/loadavg)
    "${launch[@]}" "$bin" run "$CASE" --quiet --overwrite --out "$OUT/$label-r$RANKS-$r" \
      --restart "$SETTLED" --set run.steps=$((START + STEPS)) "$@" >/dev/null 2>&1 || {
      echo "$label round $r failed"; continue; }
    python3 - "$OUT/$label-r$RANKS-$r/report.json" "$label" "$r" "$RANKS" "$STEPS" "$load" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); t = r["timers"]; steps = int(sys.argv[5])
b = {k: t[k]["busy_avg"] / steps for k in ("dem_neighbor", "dem_force", "dem_migrate", "dem_integrate", "dem_ghost")}
print(f"{sys.argv[2]} ranks {sys.argv[4]} round {sys.argv[3]} load {sys.argv[6]}: "
      + " ".join(f"{k[4:]} {v:.4f}" for k, v in b.items())
      + f" dem {sum(b.values()):.4f} s/step {r['run']['wall_s'] / steps:.4f}", flush=True)
PY
  done
done

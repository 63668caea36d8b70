#!/bin/bash
# A/B of two coloc binaries on case3-small in contact (issue 30, the rebuild): 20 steps restarted
# from the settled checkpoint that bench/scripts/contact_bench.py writes (WORK/settled.h5), one
# rank pinned to core 1, the binaries alternating, ROUNDS rounds; prints the DEM timers (busy s in
# the 20 steps) and the wall time a step.
# usage: ab.sh ROUNDS SETTLED.h5 OUTDIR LABEL=BINARY LABEL=BINARY ...
set -u
ROUNDS=$1 SETTLED=$2 OUT=$3
shift 3
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
for r in $(seq 1 "$ROUNDS"); do
  for lb in "$@"; do
    label=${lb%%=*} bin=${lb#*=}
    taskset -c 1 "$bin" run "$ROOT/bench/cases/case3-small.json" --quiet --overwrite \
      --out "$OUT/$label-$r" --restart "$SETTLED" --set run.steps=220 >/dev/null 2>&1
    python3 - "$OUT/$label-$r/report.json" "$label" "$r" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); t = r["timers"]
b = {k: t[k]["busy_avg"] for k in ("dem_neighbor", "dem_force", "dem_migrate", "dem_integrate", "dem_ghost")}
print(f"{sys.argv[2]} round {sys.argv[3]}: neighbor {b['dem_neighbor']:.3f} force {b['dem_force']:.3f} "
      f"migrate {b['dem_migrate']:.3f} integrate {b['dem_integrate']:.3f} dem {sum(b.values()):.3f} "
      f"s/step {r['run']['wall_s'] / (r['run']['steps'] - 200):.4f}")
PY
  done
done

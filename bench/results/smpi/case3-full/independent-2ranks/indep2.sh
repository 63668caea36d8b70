#!/bin/bash
# real vs simulated exchange of the independent strategy, case3-small in contact, 2 ranks, 3 steps
cd "$(dirname "$0")/../../../../.."; mkdir -p out/indep2
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
C=bench/cases/case3-small.json; DB="$(python3 bench/scripts/dense_bed.py $C)"
for i in 1 2; do
  mpirun -n 2 --bind-to core build/coloc run $C --set "$DB" --set run.steps=3 --set partition.strategy=independent --set run.timer_sync=true --quiet --overwrite --out out/indep2/i2-real-$i >/dev/null 2>&1
  python3 bench/scripts/smpi_run.py --ranks 2 --platform paper -- run $C --set "$DB" --set run.steps=3 --set partition.strategy=independent --set run.timer_sync=true --quiet --overwrite --out out/indep2/i2-sim-$i >/dev/null 2>&1
  for k in real sim; do python3 -c "
import json; r=json.load(open('out/indep2/i2-$k-$i/report.json')); t=r['timers']; s=r['run']['steps']
print('$k', $i, 'step', round(r['run']['wall_s']/s,4), 'exchange_remote avg', round(t['exchange_remote']['avg']/s*1e3,2), 'ms', 'bytes/step', r['exchange_kinds']['proxy']['bytes']//s, 'dem_force', round(t['dem_force']['avg']/s*1e3,1), 'coupling_drag', round(t.get('coupling_drag',{}).get('avg',0)/s*1e3,2))"; done
done

#!/bin/bash
# one re-balance timing run: $1 = memory|file, $2 = tag
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_mpi_yield_when_idle=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
B=${B:-build/coloc}
mpirun -n 4 $B run bench/cases/clustered.json --set partition.strategy=balanced --set partition.rebalance_interval=${IV:-5} --set partition.rebalance_threshold=1.0 --set run.steps=20 --set partition.rebalance_move=$1 --out ${OUT:-/tmp/rb}/$2 --overwrite --quiet > ${OUT:-/tmp/rb}/log-$2.txt 2>&1
python3 -c "
import json,os;r=json.load(open('${OUT:-/tmp/rb}/$2/report.json'));t=r['timers']['rebalance'];print('$1 %.4f wall/rebal  %.4f busy/rebal calls %d load %.1f'%(t['max']/t['calls'],t['busy_max']/t['calls'],t['calls'],os.getloadavg()[0]))"

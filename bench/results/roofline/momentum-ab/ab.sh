#!/bin/bash
# A/B rounds: before (/tmp/mom/before) and after (build/) alternating.
cd /work/wt-momentum
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
BED=$(python3 bench/scripts/dense_bed.py bench/cases/case3-small.json)
out=/tmp/mom/ab; mkdir -p $out
for r in $(seq 1 ${ROUNDS:-5}); do
  for v in before after; do
    if [ $v = before ]; then bin=/tmp/mom/before/coloc; bf=/tmp/mom/before/bench_fv; else bin=build/coloc; bf=build/bench/bench_fv; fi
    echo "round $r $v load $(cut -d' ' -f1 /proc/loadavg)" >> $out/load.txt
    $bf --benchmark_filter='BM_FluidChannelStep/(20|50)/' --benchmark_out=$out/bench-$v-$r.json --benchmark_out_format=json > /dev/null 2>&1
    $bin run bench/cases/case3-small.json --set "$BED" --set run.steps=10 --out $out/run-$v-$r --quiet --overwrite > /dev/null 2>&1
  done
done

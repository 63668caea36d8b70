#!/bin/bash
# A/B of bench_dem binaries on the settled 100k bed (issue 48): ROUNDS rounds, the binaries
# alternating, each restored from STATE and timing 500 sub-steps on core 1; prints per binary the
# CPU ms per 100 sub-steps, min / median / max over the rounds (the machine is shared: the
# minimum is the least disturbed run), and the ns per particle-step of the median.
# usage: [CASE=case.json] ab_bed.sh ROUNDS STATE LABEL=BINARY ...
set -u
ROUNDS=$1 STATE=$2
shift 2
declare -A t
for r in $(seq 1 "$ROUNDS"); do
  for lb in "$@"; do
    label=${lb%%=*} bin=${lb#*=}
    ms=$(env ${CASE:+DEM_BED_CASE=$CASE} DEM_BED_LOAD="$STATE" DEM_BED_SETTLE=0 taskset -c 1 "$bin" \
      --benchmark_filter=DemBed 2>/dev/null | awk '/BM_DemBed/ {print $4}')
    t[$label]="${t[$label]:-} $ms"
  done
done
for lb in "$@"; do
  label=${lb%%=*}
  echo "${t[$label]}" | tr ' ' '\n' | grep . | sort -n | awk -v l="$label" \
    '{a[NR]=$1} END {m=a[int((NR+1)/2)]; printf "%-10s CPU ms/100 steps min %s median %s max %s (%d runs): %.1f ns a particle-step (median)\n", l, a[1], m, a[NR], NR, m*1e-3/100/1e5*1e9}'
done

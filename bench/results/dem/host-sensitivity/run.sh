#!/bin/bash
# Why coloc's DEM rate moves with the host more than LAMMPS's (issue 30): on each of the two
# vCPUs in turn, the latency of a dependent load over 1 MiB and 16 MiB (bench_peak BM_Chase) and
# one round of the settled 100k bed (LAMMPS gran/hertz/history, then coloc), ROUNDS times.
# usage: run.sh ROUNDS BUILD_DIR BED_DIR (BED_DIR holds bed.state and bed.data; docs/benchmarks.md)
set -u
ROUNDS=${1:-4} BUILD=${2:-build} BED=${3:-.}
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
for r in $(seq 1 "$ROUNDS"); do
  for c in 0 1; do
    chase=$(taskset -c $c "$BUILD/bench/bench_peak" --benchmark_filter='BM_Chase/(1|16)$' \
      --benchmark_min_time=0.2 2>/dev/null | awk '/BM_Chase/{sub("seconds_per_load=","",$NF); printf "%s=%s ", $1, $NF}')
    dem=$(python3 "$ROOT/bench/scripts/dem_bed_rounds.py" --rounds 1 --core $c --peers "$ROOT/bench/peers" \
      lammps:"$BED/bed.data" coloc:main:"$BUILD/bench/bench_dem":"$BED/bed.state" 2>&1 |
      sed -nE 's/^  (lammps|coloc main) +wall +[0-9.]+ M +cpu +([0-9.]+) M.*/\1 \2/p' |
      awk '{v[$1]=$NF} END{printf "lammps_cpu=%sM coloc_cpu=%sM ratio=%.2f", v["lammps"], v["coloc"], v["coloc"]/v["lammps"]}')
    echo "round $r $(date -u +%H:%M:%S) core $c load $(cut -d' ' -f1 /proc/loadavg) $chase $dem"
  done
done

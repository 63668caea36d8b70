#!/usr/bin/env bash
# bench/scripts/many_core_check.sh [OUT]
#
# The many-core check of the performance model and of the SimGrid simulation (docs/smpi.md,
# "Checked against a 16-core machine"): real runs of case2-small and of case3-small with its bed
# in contact at 1, 2, 4, 8 and 16 ranks (RANKS), compared with bench/scripts/model.py calibrated
# on the 1-rank runs only (bench/scripts/validate_model.py --ranks); then the same points
# simulated by the SMPI build on a one-node platform of this machine's core count, so simulated,
# modelled and measured step times and shares sit side by side (smpi_vs_measured.py). case3-small's
# bed starts dense and touching (dense_bed.py), so the SMPI build, which cannot read a
# checkpoint, times the same state. For a machine with 16 idle cores: the real runs took 9
# minutes there with REPEATS=5 (about 5.5 with the default 3), the simulations about 1 minute.
# Writes OUT (default out/many-core):
#   machine.txt              lscpu, memory, load before and after
#   model/validate-*.txt     model vs measured per rank count (validate_model.py's table)
#   smpi/CASE-npN/           the simulated points (smpi_scaling.py)
#   smpi_vs_measured.md      simulated vs measured vs model, per case and rank count
#   runs/                    every run's report.json and log
#
# Environment: COLOC (build/coloc), BENCH (build/bench), SMPI_BUILD (build-smpi; the simulations
# are skipped when it has no coloc), RANKS (2,4,8,16), REPEATS (3), STEPS2 (10), STEPS3 (5),
# PYTHON (python3).
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=$(mkdir -p "${1:-$root/out/many-core}" && cd "${1:-$root/out/many-core}" && pwd)
COLOC=${COLOC:-$root/build/coloc}
BENCH=${BENCH:-$root/build/bench}
SMPI_BUILD=${SMPI_BUILD:-$root/build-smpi}
RANKS=${RANKS:-2,4,8,16}
REPEATS=${REPEATS:-3}
STEPS2=${STEPS2:-10} # case2-small's steps a run (SMPI simulates a step of it slowly)
STEPS3=${STEPS3:-5}  # case3-small's
PY=${PYTHON:-python3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=${OMPI_MCA_rmaps_base_oversubscribe:-1}
export OMPI_MCA_btl_vader_single_copy_mechanism=${OMPI_MCA_btl_vader_single_copy_mechanism:-none}
export PYTHONUNBUFFERED=1
runs=$out/runs
mkdir -p "$runs" "$out/model" "$out/smpi"
t0=$(date +%s)
stamp() { echo "[many_core_check +$(($(date +%s) - t0)) s] $*"; }

{
  echo "date: $(date -u +%FT%TZ)"
  echo "cores: $(nproc)"
  lscpu 2>/dev/null || grep -m1 "model name" /proc/cpuinfo
  free -m 2>/dev/null
  echo "load before: $(cat /proc/loadavg)"
  echo "coloc: $(mpirun -n 1 "$COLOC" --version 2>&1 | head -1)"
} >"$out/machine.txt"
cat "$out/machine.txt"

# The model against real runs: calibrated at 1 rank, predicted at RANKS (wall timer: an idle
# machine; the median of the repeats).
common=(--ranks "$RANKS" --repeats "$REPEATS" --timer wall --coloc "$COLOC" --bench "$BENCH"
        --out "$out/model")
stamp "case2-small at 1,$RANKS ranks, $STEPS2 steps (validate_model.py)"
"$PY" "$root/bench/scripts/validate_model.py" --cases "$root/bench/cases/case2-small.json" \
  --steps "$STEPS2" --runs "$runs/case2" "${common[@]}" 2>&1 | tail -n 40
stamp "case3-small in contact at 1,$RANKS ranks, $STEPS3 steps (validate_model.py)"
"$PY" "$root/bench/scripts/validate_model.py" --cases "$root/bench/cases/case3-small.json" \
  --dense-bed --steps "$STEPS3" --runs "$runs/case3" "${common[@]}" 2>&1 | tail -n 40

# The same points simulated on one node of this machine's cores (each burst timed on its core),
# the simulations side by side (one core each) once the real runs are over.
if [[ -e $SMPI_BUILD/coloc ]]; then
  plat=$out/smpi/one-node.xml
  cat >"$plat" <<EOF
<?xml version='1.0'?>
<!DOCTYPE platform SYSTEM "https://simgrid.org/simgrid.dtd">
<!-- one node of $(nproc) cores; ranks talk through shared memory (the loopback) -->
<platform version="4.1">
  <cluster id="node" prefix="node-" suffix="" radical="0-0" speed="1Gf" core="$(nproc)"
           bw="12.5GBps" lat="0.5us" loopback_bw="8GBps" loopback_lat="0.3us"/>
</platform>
EOF
  # one simulation at a time: side by side, ten simulations slowed each other's bursts (a
  # 1-rank case3-small simulated 63 % slower than measured); run.timer_sync as in the real runs,
  # so the wait for the slowest rank is booked to `wait` in both.
  stamp "case2-small and case3-small simulated at 1,$RANKS ranks (smpi_scaling.py)"
  for n in 1 ${RANKS//,/ }; do
    "$PY" "$root/bench/scripts/smpi_scaling.py" "$root/bench/cases/case2-small.json" \
      --ranks "$n" --strategies uniform --platform "$plat" --steps "$STEPS2" \
      --set run.timer_sync=true --smpi-build "$SMPI_BUILD" --out "$out/smpi/case2-small-np$n" \
      >"$out/smpi/case2-small-np$n.log" 2>&1
    "$PY" "$root/bench/scripts/smpi_scaling.py" "$root/bench/cases/case3-small.json" \
      --ranks "$n" --strategies uniform --platform "$plat" --steps "$STEPS3" --dense-bed \
      --set run.timer_sync=true --smpi-build "$SMPI_BUILD" --out "$out/smpi/case3-small-np$n" \
      >"$out/smpi/case3-small-np$n.log" 2>&1
  done
  stamp "simulations done"
  "$PY" "$root/bench/scripts/smpi_vs_measured.py" --model "$out/model" --smpi "$out/smpi" \
    --out "$out/smpi_vs_measured.md"
else
  stamp "no SMPI build at $SMPI_BUILD: simulated points skipped"
fi

echo "load after: $(cat /proc/loadavg)" >>"$out/machine.txt"
stamp "done: $out"

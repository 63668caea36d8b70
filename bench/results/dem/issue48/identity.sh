#!/bin/bash
# Bit-identity of two coloc builds (issue 48): the saved states after 150 DEM sub-steps (with
# rebuilds and, in the new build, prunes) on 1, 2 and 3 ranks, compared byte for byte.
#  - the 100k bed (bench/cases/dem-bed.json, particles only): restarted from BED_CK (a coloc
#    checkpoint of the settled bed) for 150 sub-steps, checkpoint at the end;
#  - case3-small in contact (coupled: 15 steps of 10 sub-steps) restarted from C3_CK (the settled
#    checkpoint of bench/scripts/contact_bench.py, step 200).
# The checkpoints' /particles groups (positions, velocities, spins, forces, histories, ...) and,
# for the coupled case, the fluid's fields are compared with h5diff; `identical` or the first
# differences are printed. Extra arguments (e.g. --set particles.force_isa=avx512) go to the
# NEW runs only.
# usage: identity.sh BASE_COLOC NEW_COLOC BED_CK C3_CK OUT [coloc run arguments for NEW]
set -u
BASE=$1 NEW=$2 BED_CK=$3 C3_CK=$4 OUT=$5
shift 5
ROOT=$(cd "$(dirname "$0")/../../../.." && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
  OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
bedStart=$(h5dump -a /particles/steps "$BED_CK" 2>/dev/null | awk '/\(0\)/ {print $2}')
c3Start=$(h5dump -a /particles/steps "$C3_CK" 2>/dev/null | awk '/\(0\)/ {print $2}')
echo "bed checkpoint at DEM step ${bedStart:-?}, case3-small checkpoint at DEM step ${c3Start:-?}"
for n in 1 2 3; do
  for side in base new; do
    bin=$BASE extra=()
    [[ $side == new ]] && bin=$NEW extra=("$@")
    mpirun -n "$n" --bind-to none "$bin" run "$ROOT/bench/cases/dem-bed.json" --quiet --overwrite \
      --out "$OUT/bed-$side-$n" --restart "$BED_CK" --set run.steps=$((bedStart + 150)) \
      --set output.checkpoint_interval=100000 "${extra[@]}" >"$OUT/bed-$side-$n.log" 2>&1 ||
      echo "bed $side $n ranks failed (see $OUT/bed-$side-$n.log)"
    mpirun -n "$n" --bind-to none "$bin" run "$ROOT/bench/cases/case3-small.json" --quiet \
      --overwrite --out "$OUT/c3-$side-$n" --restart "$C3_CK" --set run.steps=215 \
      --set output.checkpoint_interval=100000 "${extra[@]}" >"$OUT/c3-$side-$n.log" 2>&1 ||
      echo "case3-small $side $n ranks failed (see $OUT/c3-$side-$n.log)"
  done
  for c in bed c3; do
    a=$OUT/$c-base-$n/checkpoint.h5 b=$OUT/$c-new-$n/checkpoint.h5
    if h5diff -q "$a" "$b" /particles /particles >/dev/null 2>&1 &&
      { [[ $c == bed ]] || h5diff -q "$a" "$b" /fluid /fluid >/dev/null 2>&1; }; then
      echo "$c, $n ranks: identical ($(h5dump -a /particles/rebuilds "$b" | awk '/\(0\)/ {print $2}') rebuilds in all)"
    else
      echo "$c, $n ranks: DIFFERENT"; h5diff "$a" "$b" /particles /particles | head -5
    fi
  done
done

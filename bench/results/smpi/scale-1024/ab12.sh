#!/usr/bin/env bash
# ab12.sh ROUNDS (from the repository root, after cmake/setup.sh and cmake/setup-smpi.sh): real vs simulated (new settings / old settings) at 1 and 2 ranks, alternating
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
cd "$(git rev-parse --show-toplevel)"
SMPI=${SMPI:-build-smpi}
BED="$(python3 bench/scripts/dense_bed.py bench/cases/case3-small.json)"
o=${OUT:-out/ab12}; mkdir -p $o
for r in $(seq 1 $1); do
 for c in case2-small case3-small; do
  if [ $c = case2-small ]; then extra=(--set run.steps=10); else extra=(--set "$BED" --set run.steps=3); fi
  for n in 1 2; do
   mpirun -np $n --bind-to core build/coloc run bench/cases/$c.json "${extra[@]}" --set run.timer_sync=true --quiet --overwrite --out $o/real-$c-$n-$r > /dev/null 2>&1
   python3 bench/scripts/smpi_run.py --ranks $n --smpi-build $SMPI --platform paper -- run bench/cases/$c.json "${extra[@]}" --set run.timer_sync=true --quiet --overwrite --out $o/new-$c-$n-$r > /dev/null 2>&1
   python3 bench/scripts/smpi_run.py --ranks $n --smpi-build $SMPI --platform paper --coll default --cfg smpi/send-is-detached-thresh:65536 -- run bench/cases/$c.json "${extra[@]}" --set run.timer_sync=true --quiet --overwrite --out $o/old-$c-$n-$r > /dev/null 2>&1
  done
 done
done
OUTDIR=$o python3 - <<'PY'
import json,glob,os,statistics as st,collections
d=collections.defaultdict(list)
for f in glob.glob(os.environ['OUTDIR']+'/*/report.json'):
    k=f.split('/')[-2]; kind,case,n,r=k.split('-')[0],'-'.join(k.split('-')[1:3]),k.split('-')[3],k.split('-')[4]
    j=json.load(open(f)); w=j['run']['wall_s']/j['run']['steps']
    t=j['timers']; g=lambda p: t[p]['avg']/j['run']['steps'] if p in t else 0
    d[(case,n,kind)].append((w,g('fluid_pressure_assemble'),g('fluid_pressure_solve'),j['fractions']['fv'],j['fractions'].get('wait',0)))
for case in ['case2-small','case3-small']:
  for n in ['1','2']:
    real=d[(case,n,'real')]
    if not real: continue
    mr=st.median(x[0] for x in real)
    line=f"{case} np{n} real {mr:.4f} ({min(x[0] for x in real):.4f}-{max(x[0] for x in real):.4f}) set-up {st.median(x[1] for x in real)*1e3:.1f} ms solve {st.median(x[2] for x in real)*1e3:.1f} ms fluid {st.median(x[3] for x in real)*100:.1f}% wait {st.median(x[4] for x in real)*100:.1f}%"
    print(line)
    for kind in ['new','old']:
      v=d[(case,n,kind)]
      if not v: continue
      m=st.median(x[0] for x in v)
      print(f"   {kind}: {m:.4f} ({(m/mr-1)*100:+.0f} %) set-up {st.median(x[1] for x in v)*1e3:.1f} ms solve {st.median(x[2] for x in v)*1e3:.1f} ms fluid {st.median(x[3] for x in v)*100:.1f}% wait {st.median(x[4] for x in v)*100:.1f}%")
PY

import json, glob, statistics as st, re
d = 'bench/results/roofline/momentum-ab/raw'
def mmm(xs): xs = sorted(xs); return f'{min(xs):.4g} / {st.median(xs):.4g} / {max(xs):.4g}'
res = {}
for v in ('before', 'after'):
    for f in sorted(glob.glob(f'{d}/bench-{v}-*.json')):
        for b in json.load(open(f))['benchmarks']:
            n = b['name'].split('/')[1]
            res.setdefault((v, 'channel%s step ms' % n), []).append(b['real_time'])
            res.setdefault((v, 'channel%s fluid_momentum ms/step' % n), []).append(b['fluid_momentum'] * 1e3)
    for f in sorted(glob.glob(f'{d}/run-{v}-*/report.json')):
        r = json.load(open(f))
        t = r['timers']['fluid_momentum']
        steps = r['run']['steps']
        res.setdefault((v, 'case3-small fluid_momentum ms/step'), []).append(t['max'] / steps * 1e3)
        res.setdefault((v, 'case3-small wall s (10 steps)'), []).append(r['run']['wall_s'])
keys = sorted({k for _, k in res})
for k in keys:
    b, a = res[('before', k)], res[('after', k)]
    print(f'{k:38s} before {mmm(b):28s} after {mmm(a):28s} median ratio {st.median(b)/st.median(a):.2f}x  (n={len(b)},{len(a)})')

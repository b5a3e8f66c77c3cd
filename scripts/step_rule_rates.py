#!/usr/bin/env python3
"""The step rule of `plinth diagnose --machine` on ROSS runs (docs/diagnose-verdict.md "Session 41 (stepsd17b)").

Usage: python3 scripts/step_rule_rates.py MACHINE:OUTDIR ...

OUTDIR holds, per run CASE-SEED (made by scripts/ross_unseen.py --machine
MACHINE), CASE-SEED.json, the output of `plinth diagnose RUN --json --machine
FILE`, and CASE-SEED.err, its stderr. Prints:

- per (machine, case, step, effect, bearing), over the runs that named
  exactly the truth's effects (scripts/bench_unseen.py's `judge`): the
  step's machine-level gap change (mean, spread over seeds), the median of
  its `machine_gap_change_sd`, and RMS (change - mean)/sd (about 1 when
  the sd means what it says). The sd of a step whose gap falls is only in
  the JSON with a measuring build that computes it on every step (session
  41's patch, in the docs page); the parts (changed bearings, the others,
  the measurements) and session 40's sd (changed and measurements only)
  are read from the STEP_SD lines such a build writes on stderr;
- per case, the right runs whose step rule fires (a kept step whose gap
  rose by more than MACHINE_STEP_NOISE_SD = 2.33 sd, or rose with no sd),
  with the sd given and with session 40's.
"""
import json, math, os, re, sys, glob
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_unseen as bu
K = 2.33
rows = {}
fa = {}
rising = []
for arg in sys.argv[1:]:
    mach, out = arg.split(':')
    bu.MACHINE = mach
    for jf in sorted(glob.glob(os.path.join(out, '*.json'))):
        name = os.path.basename(jf)[:-5]
        case, seed = name.rsplit('-', 1)
        try:
            d = json.load(open(jf))
        except Exception:
            continue
        parts = [tuple(float(x) for x in re.findall(r'=([-0-9.e+]+)', l))
                 for l in open(jf[:-5] + '.err') if l.startswith('STEP_SD')]
        named = [(s['effect'], s['bearing']) for s in d['steps'] if not s.get('dropped')]
        r = {'named': named}
        verdict = bu.judge(case, r)
        k = 0
        rising_old = rising_new = False
        nsteps = 0
        for i, s in enumerate(d['steps']):
            if s.get('dropped'):
                continue
            sd = s.get('machine_gap_change_sd')
            b, a = s.get('machine_gap_before'), s.get('machine_gap_after')
            p = None
            if sd is not None:
                p = parts[k] if k < len(parts) else None
                k += 1
            if b is None or a is None:
                continue
            nsteps += 1
            ch = a - b
            old = math.sqrt(p[0]**2 + p[2]**2) if p else None
            if verdict == 'right':
                rows.setdefault((mach, case, i + 1, s['effect'], s['bearing']), []).append((int(seed), ch, sd, old, p))
            if ch > 0 and verdict == 'right':
                rising.append((mach, case, int(seed), i + 1, s['effect'], s['bearing'], round(ch, 4),
                               round(ch / sd, 2) if sd else None, round(ch / old, 2) if old else None))
            if ch > 0:
                if sd is None or ch > K * sd: rising_new = True
                if parts and (old is None or ch > K * old): rising_old = True
        key = (mach, case)
        f = fa.setdefault(key, {'runs': 0, 'right': 0, 'right_steps': 0, 'fa_new': 0, 'fa_old': 0, 'trusted': 0, 'wrong': 0, 'other': 0})
        f['runs'] += 1
        if verdict == 'right':
            f['right'] += 1
            if nsteps: f['right_steps'] += 1
            f['fa_new'] += rising_new
            f['fa_old'] += rising_old
            f['trusted'] += d['trusted']
        elif verdict == 'wrong':
            f['wrong'] += 1
        else:
            f['other'] += 1
print('RMS z per step (right runs):')
print('machine case step effect bearing | n | mean change, spread | median sd new | RMS z new | median sd s40 | RMS z s40 | med parts changed/shared/direct')
for key, v in sorted(rows.items()):
    v = [x for x in v if x[2] is not None]
    if len(v) < 2: 
        print(key, 'n', len(v)); continue
    ch = [x[1] for x in v]; m = sum(ch) / len(ch)
    spread = math.sqrt(sum((c - m)**2 for c in ch) / (len(ch) - 1))
    med = lambda a: sorted(a)[len(a) // 2]
    zn = math.sqrt(sum(((x[1] - m) / x[2])**2 for x in v) / len(v))
    zo = math.sqrt(sum(((x[1] - m) / x[3])**2 for x in v if x[3]) / max(1, len([x for x in v if x[3]])))
    pp = [x[4] for x in v if x[4]]
    print(*key, '|', len(v), '| %.4f %.4f | %.5f | %.2f | %.5f | %.2f | %s' % (m, spread, med([x[2] for x in v]), zn, med([x[3] for x in v if x[3]]), zo,
          '/'.join('%.5f' % med([q[j] for q in pp]) for j in range(3))))
print('\nfalse alarms (right runs whose step rule fires):')
tot = {'right': 0, 'right_steps': 0, 'fa_new': 0, 'fa_old': 0}
for key, f in sorted(fa.items()):
    print(*key, f)
    for t in tot: tot[t] += f[t]
print('total', tot)
print('\nrising steps on right runs (machine, case, seed, step, effect, bearing, change, change/sd, change/sd session 40):')
for r in rising: print(*r)
if '-v' in os.environ.get('ANA', ''):
    for key, v in sorted(rows.items()):
        for x in v: print(key, x)

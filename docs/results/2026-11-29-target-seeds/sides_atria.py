# Nearer and farther parts of the cracks at [2,inf) on the atria, row minus full, seed-aware bootstrap (as seeds.py).
import json, random
A='out/experiments/ablation/eval/atrium-nerfstudio'; N='out/experiments/target_seeds_nearer/atrium-nerfstudio'
def load(p): return {r['index']: r for r in map(json.loads, open(p))}
seeds=[0,1,2,3]
def part(row, s):
    d=load(f'{A}/results_{row}-s{s}_depth.jsonl'); n=load(f'{N}/results_{row}-s{s}.jsonl')
    out={}
    for i,r in d.items():
        if r['bin']!=3 or r.get('crack_rate') is None: continue
        out[i]=(100*r['crack_rate'],100*n[i]['crack_rate'],100*(r['crack_rate']-n[i]['crack_rate']))
    return out
P={(row,s):part(row,s) for row in ('full','pixel_supports','dense_decoder') for s in seeds}
keys=sorted(P[('full',0)])
for row in ('full','pixel_supports','dense_decoder'):
    m=[sum(P[(row,s)][i][k] for s in seeds for i in keys)/(len(seeds)*len(keys)) for k in range(3)]
    print(f"{row}: cracks {m[0]:.3f} nearer {m[1]:.3f} farther {m[2]:.3f}  ({len(keys)} pairs, 4 seeds)")
for row in ('pixel_supports','dense_decoder'):
    txt=[]
    for k,name in enumerate(('cracks','nearer','farther')):
        d={s:[P[(row,s)][i][k]-P[('full',s)][i][k] for i in keys] for s in seeds}
        per=[sum(d[s])/len(keys) for s in seeds]; mean=sum(per)/4
        rng=random.Random(0); bs=[]
        for _ in range(2000):
            ss=[seeds[rng.randrange(4)] for _ in seeds]; ps=[rng.randrange(len(keys)) for _ in keys]
            bs.append(sum(d[s][p] for s in ss for p in ps)/(len(ss)*len(ps)))
        bs.sort()
        txt.append(f"{name} {mean:+.3f} [{bs[50]:+.3f}, {bs[1949]:+.3f}] (seeds {' '.join(f'{x:+.3f}' for x in per)})")
    print(f"{row} - full:", ' | '.join(txt))

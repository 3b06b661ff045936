# Paired bootstrap (2000 resamples, seed 0) of per-pair differences between two methods on the same pairs, per set
# and bin (every set folder that holds results of method a). A method may be "m1+m2": the per-pair mean of several
# (e.g. two seeds of a row). Usage: python3 paired.py <eval out folder> <method a> <method b> [all,3]  (bin 3 = [2,inf))
import json, os, sys, random
root, a, b = sys.argv[1], sys.argv[2], sys.argv[3]
bins = sys.argv[4].split(',') if len(sys.argv) > 4 else ['all', '3']
FIELDS = [('psnr', 1), ('hole_rate', 100), ('crack_rate', 100), ('normal_deg', 1), ('lpips_squeeze', 1)]
def load_one(s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
def load(s, spec):
    runs = [load_one(s, m) for m in spec.split('+')]
    keys = [k for k in runs[0] if all(k in r for r in runs)]  # file order, as the single-method results
    def avg(k, f):  # None where a method has no such measure (identity: no holes or cracks)
        v = [r[k].get(f) for r in runs]
        return None if None in v else sum(v) / len(v)
    return {k: dict(runs[0][k], **{f: avg(k, f) for f, _ in FIELDS}) for k in keys}
sets = sorted(d for d in os.listdir(root) if os.path.exists(f"{root}/{d}/results_{a.split('+')[0]}.jsonl"))
for s in sets:
    A, B = load(s, a), load(s, b)
    for bn in bins:
        keys = [k for k in A if k in B and (bn == 'all' or A[k]['bin'] == int(bn))]
        out = []
        for f, sc in FIELDS:
            ks = [k for k in keys if A[k][f] is not None and B[k][f] is not None]
            if not ks:
                continue
            d = [sc * (A[k][f] - B[k][f]) for k in ks]
            m = sum(d) / len(d)
            rng = random.Random(0); bs = []
            for _ in range(2000):
                x = [d[rng.randrange(len(d))] for _ in d]; bs.append(sum(x) / len(x))
            bs.sort()
            va = sum(sc * A[k][f] for k in ks) / len(ks)
            out.append(f"{f} {va:.2f} {m:+.2f} [{bs[50]:+.2f}, {bs[1949]:+.2f}]" if f != 'lpips_squeeze' else f"lpips {m:+.3f}")
        print(s, bn, len(keys), ' | '.join(out))

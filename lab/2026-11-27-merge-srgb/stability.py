# Holes and cracks (percent of masked pixels) at the widest baselines, [2,inf), for the third round's choices against
# full@px0.85, both seeds averaged per pair. Usage: python3 stability.py <eval out folder> [<eval out folder> ...]
import json, os, sys
def rows(root, s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
for root in sys.argv[1:]:
    for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
        out = []
        for m in ('full', 'full_merge2s', 'full_merge2sf03', 'full_merge2sf04'):
            a, b = rows(root, s, f"{m}_px0_85"), rows(root, s, f"{m}_s1_px0_85")
            keys = [k for k in a if k in b and a[k]['bin'] == 3]
            mean = lambda f: 100 * sum((a[k][f] + b[k][f]) / 2 for k in keys) / len(keys)
            out.append(f"{m[5:] or 'full'} {mean('hole_rate'):.2f} / {mean('crack_rate'):.2f}")
        print(f"{s} [2,inf) holes / cracks: " + "; ".join(out))

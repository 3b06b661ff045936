# Cracks split by side: per set and bin, each row's crack rate (% of smooth neighbour pairs; seeds averaged per pair),
# its nearer part (scored with scoring.crack_side = nearer) and farther part (any - nearer, same pairs), and the
# paired bootstrap 95% interval (2000 resamples, seed 0) of the full model minus each other row.
# Usage: python3 sides.py <any folder> <nearer folder> [bins, e.g. all,3] [name=m1+m2 ...]   (bin 3 = [2,inf))
import json, os, sys, random
def load(root, s, spec):
    runs = [{r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))} for m in spec.split('+')]
    out = {}
    for k in runs[0]:
        v = [r[k].get('crack_rate') if k in r else None for r in runs]
        if None not in v:
            out[k] = (runs[0][k]['bin'], 100 * sum(v) / len(v))
    return out
def interval(d):
    rng = random.Random(0); bs = []
    for _ in range(2000):
        x = [d[rng.randrange(len(d))] for _ in d]; bs.append(sum(x) / len(x))
    bs.sort()
    return f"{sum(d) / len(d):+.3f} [{bs[50]:+.3f}, {bs[1949]:+.3f}]"

def main():
    ANY, NEAR = sys.argv[1], sys.argv[2]
    BINS = sys.argv[3].split(',') if len(sys.argv) > 3 else ['all', '3']
    ROWS = [('full', 'full+full_s1'), ('pixel', 'pixel_supports+pixel_supports_s1'),
            ('dense', 'dense_decoder+dense_decoder_s1')]
    ROWS += [tuple(a.split('=', 1)) for a in sys.argv[4:]]  # more rows: name=method+method
    for s in sorted(d for d in os.listdir(ANY) if os.path.exists(f"{ANY}/{d}/results_full.jsonl")):
        data = {}
        for name, spec in ROWS:
            a, n = load(ANY, s, spec), load(NEAR, s, spec)
            data[name] = {k: (a[k][0], a[k][1], n[k][1], a[k][1] - n[k][1]) for k in a if k in n}
        for bn in BINS:
            keys = [k for k in data['full'] if all(k in data[r] for r, _ in ROWS) and (bn == 'all' or data['full'][k][0] == int(bn))]
            print(f"## {s}, bin {'all' if bn == 'all' else '[2,inf)' if bn == '3' else bn}, {len(keys)} pairs")
            print("| row | cracks | nearer | farther | Δ cracks vs full | Δ nearer | Δ farther |")
            print("|---|---|---|---|---|---|---|")
            for name, _ in ROWS:
                m = [sum(data[name][k][c] for k in keys) / len(keys) for c in (1, 2, 3)]
                diffs = ' |  | ' if name == 'full' else ' | '.join(
                    interval([data['full'][k][c] - data[name][k][c] for k in keys]) for c in (1, 2, 3))
                print(f"| {name} | {m[0]:.3f} | {m[1]:.3f} | {m[2]:.3f} | {diffs} |")
            print()

if __name__ == '__main__':
    main()

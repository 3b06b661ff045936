# Seed-aware paired bootstrap: method a minus method b, run by run over training seeds, on the same pairs.
# The pair-only intervals of paired.py treat two trained runs as fixed; this one resamples the seeds as well
# (2000 resamples, seed 0): each resample draws seeds with replacement (seed k of a against seed k of b, which share
# initialisation and data order) and then pairs with replacement, and averages a - b over both.
# Usage: python3 seeds.py <eval out folder> <a> <b> <seeds, e.g. 2,3,4,5> [bins, e.g. all,3]
# <a>/<b> name a results file with {s} for the seed's suffix: "full_behind{s}_split" reads results_full_behind_split
# for seed 0 ("" suffix) and results_full_behind_s2_split for seed 2.
# {k} is the seed number itself, for names such as "full-s{k}" (results_full-s0 ... results_full-s3).
import json, os, random, sys


def seed_interval(d, seeds, n):
    """95% interval of the mean of d[seed][pair] over seeds and n pairs, both drawn with replacement (2000 draws)."""
    rng = random.Random(0); bs = []
    for _ in range(2000):
        ss = [seeds[rng.randrange(len(seeds))] for _ in seeds]
        ps = [rng.randrange(n) for _ in range(n)]
        bs.append(sum(d[k][p] for k in ss for p in ps) / (len(ss) * len(ps)))
    bs.sort()
    return bs[50], bs[1949]


def main():
    root, a, b, seeds = sys.argv[1], sys.argv[2], sys.argv[3], [int(x) for x in sys.argv[4].split(',')]
    bins = sys.argv[5].split(',') if len(sys.argv) > 5 else ['all', '3']
    FIELDS = [('psnr', 1, 2), ('hole_rate', 100, 2), ('crack_rate', 100, 2), ('normal_deg', 1, 2), ('lpips_squeeze', 1, 3)]
    def path(s, spec, seed):
        return f"{root}/{s}/results_{spec.format(s='' if seed == 0 else f'_s{seed}', k=seed)}.jsonl"
    def load(s, spec, seed):
        return {r['index']: r for r in map(json.loads, open(path(s, spec, seed)))}
    sets = sorted(d for d in os.listdir(root) if all(os.path.exists(path(d, m, k)) for m in (a, b) for k in seeds))
    for s in sets:
        A = {k: load(s, a, k) for k in seeds}
        B = {k: load(s, b, k) for k in seeds}
        for bn in bins:
            keys = [i for i in A[seeds[0]] if all(i in A[k] and i in B[k] for k in seeds)
                    and (bn == 'all' or A[seeds[0]][i]['bin'] == int(bn))]
            out = []
            for f, sc, dp in FIELDS:
                ks = [i for i in keys if all(A[k][i].get(f) is not None and B[k][i].get(f) is not None for k in seeds)]
                if not ks:
                    continue
                d = {k: [sc * (A[k][i][f] - B[k][i][f]) for i in ks] for k in seeds}
                per_seed = [sum(d[k]) / len(ks) for k in seeds]
                m = sum(per_seed) / len(seeds)
                lo, hi = seed_interval(d, seeds, len(ks))
                seeds_txt = ' '.join(f"{x:+.{dp}f}" for x in per_seed)
                out.append(f"{f} {m:+.{dp}f} [{lo:+.{dp}f}, {hi:+.{dp}f}] (seeds {seeds_txt})")
            print(s, bn, len(keys), 'pairs,', len(seeds), 'seeds |', ' | '.join(out))


if __name__ == '__main__':
    main()

# Per-seed means of each method on one set (PSNR over all bins; holes and cracks at the last bin, in points), and the
# spread of the seeds: the standard deviation of a row's per-seed PSNR, i.e. the training noise a one-seed figure has.
# Usage: python3 per_seed.py <eval out folder> <set> <seeds, e.g. 0,1,2,3,4,5> <method with {s}> [<method> ...]
import json, statistics, sys
root, ds, seeds, methods = sys.argv[1], sys.argv[2], [int(x) for x in sys.argv[3].split(',')], sys.argv[4:]
def rows(m, k):
    return [json.loads(l) for l in open(f"{root}/{ds}/results_{m.format(s='' if k == 0 else f'_s{k}')}.jsonl")]
last = 3
print(f"{'method':32s} " + ' '.join(f"{'s' + str(k):>7s}" for k in seeds) + "    mean      sd | holes@3 cracks@3 (seed mean)")
for m in methods:
    ps, hs, cs = [], [], []
    for k in seeds:
        r = rows(m, k)
        ps.append(sum(x['psnr'] for x in r) / len(r))
        b = [x for x in r if x['bin'] == last]
        hs.append(100 * sum(x['hole_rate'] for x in b) / len(b))
        cs.append(100 * sum(x['crack_rate'] for x in b) / len(b))
    print(f"{m:32s} " + ' '.join(f"{p:7.2f}" for p in ps) +
          f" {statistics.mean(ps):7.2f} {statistics.stdev(ps):7.3f} | {statistics.mean(hs):7.2f} {statistics.mean(cs):7.2f}")

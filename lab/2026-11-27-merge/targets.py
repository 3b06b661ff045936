# Issue 16's two targets on an evaluation folder, with both seeds averaged per pair and paired bootstrap 95%
# intervals (2000 resamples, seed 0). Usage: python3 targets.py <eval out folder>
import json, os, random, sys
root = sys.argv[1]
def load(s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
def method(s, name, budget):  # two seeds: name@budget and name_s1@budget, averaged per pair
    b = budget.replace('.', '_')
    runs = [load(s, f"{name}_px{b}"), load(s, f"{name}_s1_px{b}")]
    keys = [k for k in runs[0] if k in runs[1]]
    return {k: {f: sum(r[k][f] for r in runs) / 2 for f in ('psnr', 'gaussians', 'lpips_squeeze')} for k in keys}
def interval(d):
    rng = random.Random(0)
    bs = sorted(sum(rng.choice(d) for _ in d) / len(d) for _ in range(2000))
    return sum(d) / len(d), bs[50], bs[1949]
def compare(A, B):
    keys = [k for k in A if k in B]
    m, lo, hi = interval([A[k]['psnr'] - B[k]['psnr'] for k in keys])
    ga = sum(A[k]['gaussians'] for k in keys) / len(keys)
    gb = sum(B[k]['gaussians'] for k in keys) / len(keys)
    return m, lo, hi, ga, gb
budgets = ['0.43', '0.64', '0.85']
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    fixed = {b: method(s, 'full', b) for b in budgets}
    mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
    best = max(budgets, key=lambda b: mean(fixed[b]))
    print(f"## {s}: fixed budgets (two seeds) " + ", ".join(f"px{b} {mean(fixed[b]):.2f} dB" for b in budgets)
          + f"; best px{best}")
    for name in ('full+merge2', 'full+merge2c06'):
        for b in budgets:
            M = method(s, name.replace('+', '_'), b)
            m, lo, hi, ga, gr = compare(M, fixed['0.85'])
            m2, lo2, hi2, _, gbest = compare(M, fixed[best])
            m3, lo3, hi3, _, gsame = compare(M, fixed[b])
            print(f"{name}@px{b}: {ga:.0f} Gaussians | vs px0.85: {100 * (1 - ga / gr):.1f}% fewer, "
                  f"{m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB | vs best px{best}: {gbest / ga:.2f}x fewer, "
                  f"{m2:+.3f} [{lo2:+.3f}, {hi2:+.3f}] dB | vs px{b} unmerged: {100 * (1 - ga / gsame):.1f}% fewer, "
                  f"{m3:+.3f} [{lo3:+.3f}, {hi3:+.3f}] dB")

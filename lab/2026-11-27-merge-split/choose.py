# The decision rule of 2026-11-27-merge-split.md on the development folder (one seed, full_s0), with paired
# bootstrap 95% intervals (2000 resamples, seed 0). Usage: python3 choose.py <dev eval out folder>/dev-wide
import json, random, sys
root = sys.argv[1]
def load(m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/results_{m}.jsonl"))}
def interval(d):
    rng = random.Random(0)
    bs = sorted(sum(rng.choice(d) for _ in d) / len(d) for _ in range(2000))
    return sum(d) / len(d), bs[50], bs[1949]
def compare(A, B):
    keys = sorted(k for k in A if k in B)
    m, lo, hi = interval([A[k]['psnr'] - B[k]['psnr'] for k in keys])
    return m, lo, hi, sum(A[k]['gaussians'] for k in keys) / len(keys), sum(B[k]['gaussians'] for k in keys) / len(keys)
budgets = ['0.43', '0.64', '0.85']
fixed = {b: load(f"full_px{b.replace('.', '_')}") for b in budgets}
mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
best = max(budgets, key=lambda b: mean(fixed[b]))
print("fixed budgets: " + ", ".join(f"px{b} {mean(fixed[b]):.3f} dB" for b in budgets) + f"; best px{best}")
prune, twice = [], []
for name in ('merge2s', 'merge2L2', 'merge2sL2', 'merge2sL3'):
    for b in budgets:
        M = load(f"full_{name}_px{b.replace('.', '_')}")
        m, lo, hi, g, g85 = compare(M, fixed['0.85'])
        m2, lo2, hi2, _, gbest = compare(M, fixed[best])
        print(f"{name}@px{b}: {g:.0f} Gaussians | vs px0.85: {100 * (1 - g / g85):.1f}% fewer, {m:+.3f} "
              f"[{lo:+.3f}, {hi:+.3f}] dB | vs best px{best}: {gbest / g:.2f}x fewer, {m2:+.3f} [{lo2:+.3f}, {hi2:+.3f}] dB")
        if b != '0.43' and m >= -0.05: prune.append((g, f"{name}@px{b}"))
        if m2 >= -0.1: twice.append((g, f"{name}@px{b}"))
print("pruning choice:", min(prune)[1] if prune else "none qualifies")
print("2x choice:", min(twice)[1] if twice else "none qualifies")

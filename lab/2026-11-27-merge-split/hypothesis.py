# The 2x hypothesis of the confirmation rule, on the selection sets (both seeds averaged per pair): among merge2s at
# 0.43, 0.64 and 0.85, the one with the fewest Gaussians that is within 0.1 dB (paired mean) of each set's best fixed
# budget on all three sets. Usage: python3 hypothesis.py <eval out folder>
import os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from targets import root, method, compare
budgets = ['0.43', '0.64', '0.85']
names = {'0.43': 'full_merge2s-budgets', '0.64': 'full_merge2s-budgets', '0.85': 'full_merge2s'}
sets = sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}"))
ok = []
for b in budgets:
    worst, total = 1e9, 0.0
    for s in sets:
        fixed = {c: method(s, 'full', c) for c in budgets}
        mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
        best = max(budgets, key=lambda c: mean(fixed[c]))
        m, lo, hi, ga, gb, lp = compare(method(s, names[b], b), fixed[best])
        print(f"merge2s@px{b} on {s}: {ga:.0f} Gaussians, {gb / ga:.2f}x fewer than best px{best}, "
              f"{m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB")
        worst, total = min(worst, m), total + ga
    if worst >= -0.1: ok.append((total, f"merge2s@px{b}"))
print("2x hypothesis:", min(ok)[1] if ok else "none qualifies")

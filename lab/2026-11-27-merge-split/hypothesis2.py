# The second 2x hypothesis (see the report): among the candidates, the one with the fewest Gaussians (summed over the
# selection sets, both seeds averaged per pair) within 0.1 dB (paired mean) of each set's best fixed budget on all
# three sets. Usage: python3 hypothesis2.py <eval out folder>
import os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from targets import root, method, compare
budgets = ['0.43', '0.64', '0.85']
candidates = [('full_merge2s-budgets', '0.43'), ('full_merge2s-budgets', '0.64'), ('full_merge2s', '0.85'),
              ('full_merge2sc045', '0.64'), ('full_merge2sc06', '0.64'), ('full_merge2sL2h', '0.64'),
              ('full_merge2sL2h', '0.85'), ('full_merge2s-px053', '0.53')]
sets = sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}"))
ok = []
for name, b in candidates:
    worst, total, line = 1e9, 0.0, []
    for s in sets:
        fixed = {c: method(s, 'full', c) for c in budgets}
        mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
        best = max(budgets, key=lambda c: mean(fixed[c]))
        m, lo, hi, ga, gb, lp = compare(method(s, name, b), fixed[best])
        line.append(f"{s}: {ga:.0f}, {gb / ga:.2f}x vs px{best}, {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB")
        worst, total = min(worst, m), total + ga
    label = name.replace('full_', '').replace('-budgets', '').replace('-px053', '') + f"@px{b}"
    print(f"{label}: " + " | ".join(line))
    if worst >= -0.1: ok.append((total, label))
print("2x hypothesis:", min(ok)[1] if ok else "none qualifies")

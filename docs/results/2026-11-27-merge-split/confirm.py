# The confirmation rule of 2026-11-27-merge-split.md on the fresh scenes (both seeds averaged per pair; paired
# bootstrap 95% intervals, 2000 resamples, seed 0), overall and per bin. Usage: python3 confirm.py <eval out folder>
import os, sys
exec(open(os.path.join(os.path.dirname(__file__), 'targets.py')).read().split("budgets = ['0.43'")[0])
budgets = ['0.43', '0.64', '0.85']
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    fixed = {b: method(s, 'full', b) for b in budgets}
    mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
    best = max(budgets, key=lambda b: mean(fixed[b]))
    bins = sorted({v['bin'] for v in fixed['0.85'].values()})
    print(f"## {s}: fixed budgets (two seeds) " + ", ".join(f"px{b} {mean(fixed[b]):.2f} dB" for b in budgets)
          + f"; best px{best}")
    for label, name, b, ref in (("pruning", 'full_merge2s', '0.85', '0.85'),
                                ("2x", 'full_merge2s-budgets', '0.64', best)):
        m, lo, hi, ga, gr, lp = compare(method(s, name, b), fixed[ref])
        if label == "pruning":
            verdict = "met" if ga <= 0.7 * gr and m >= -0.05 else "missed"
            saving = f"{100 * (1 - ga / gr):.1f}% fewer"
        else:
            verdict = "met" if 2 * ga <= gr and m >= -0.1 else "missed"
            saving = f"{gr / ga:.2f}x fewer"
        print(f"{label}: merge2s@px{b} vs px{ref}: {ga:.0f} vs {gr:.0f} Gaussians, {saving}, "
              f"PSNR {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, LPIPS {lp:+.4f}: {verdict}")
        for bn in bins:
            m, lo, hi, _, _, lp = compare(method(s, name, b), fixed[ref], bn)
            print(f"    bin {bn}: {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, LPIPS {lp:+.4f}")

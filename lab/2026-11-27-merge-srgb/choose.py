# The decision rules of 2026-11-27-merge-srgb.md on the selection folder (both seeds of full averaged per pair,
# paired bootstrap 95% intervals), plus, for the sRGB round, the hypothesis check against the linear test.
# Usage: python3 choose.py <eval out folder> [srgb|flatness|flatness2|flatness3]   (the folder holding the three selection sets)
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '2026-11-27-merge-split'))
from targets import method, compare, budgets  # the split report's loader: reads sys.argv[1] as the folder

root = sys.argv[1]
sets = sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}"))
# Each round: method name -> the value the pruning rule takes the largest of, and the candidates' budgets.
ROUNDS = {'srgb': ({f"merge2sr{t}": float('0.' + t) for t in ('03', '045', '06', '08')}, ['0.53', '0.64', '0.85']),
          'flatness': ({'merge2sf04': 0.4, 'merge2sf06': 0.6}, ['0.64', '0.85']),
          'flatness2': ({'merge2sf03': 0.3}, ['0.85']),
          'flatness3': ({'merge2sf03-px064': 0.3}, ['0.64'])}
round_name = sys.argv[2] if len(sys.argv) > 2 else 'srgb'
candidates, candidate_budgets = ROUNDS[round_name]
mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
fixed = {s: {b: method(s, 'full', b) for b in budgets} for s in sets}
best = {s: max(budgets, key=lambda b: mean(fixed[s][b])) for s in sets}
for s in sets:
    print(f"## {s}: " + ", ".join(f"px{b} {mean(fixed[s][b]):.3f} dB" for b in budgets) + f"; best px{best[s]}")
prune, twice = [], []
for cand in candidates:
    for b in candidate_budgets:
        name = f"full_{cand}"
        ok_prune, ok_twice, ratios = True, True, []
        print(f"{cand}@px{b}:")
        for s in sets:
            M = method(s, name, b)
            m, lo, hi, g, g85, lp = compare(M, fixed[s]['0.85'])
            m2, lo2, hi2, _, gb, _ = compare(M, fixed[s][best[s]])
            ratios.append(g / gb)
            ok_prune &= m >= -0.03
            ok_twice &= m2 >= -0.05
            print(f"    {s}: {g:.0f} Gaussians | vs px0.85 {100 * (1 - g / g85):.1f}% fewer, {m:+.3f} [{lo:+.3f}, "
                  f"{hi:+.3f}] dB, LPIPS {lp:+.4f} | vs best px{best[s]} {gb / g:.2f}x fewer, {m2:+.3f} "
                  f"[{lo2:+.3f}, {hi2:+.3f}] dB")
        if b == '0.85' and ok_prune: prune.append((candidates[cand], f"{cand}@px{b}"))
        if ok_twice: twice.append((sum(ratios) / len(ratios), f"{cand}@px{b}"))
choice = max(prune)[1] if prune else None
print("pruning choice:", choice or "none qualifies")
print("2x choice:", min(twice)[1] if twice else "none qualifies")
if choice and round_name == 'srgb':
    tau = choice.split('@')[0].replace('merge2sr', '')
    print(f"hypothesis: merge2sr{tau}@px0.85 against the linear test merge2s@px0.85")
    holds = True
    for s in sets:
        A, L = method(s, f"full_merge2sr{tau}", '0.85'), method(s, 'full_merge2s', '0.85')
        m, lo, hi, ga, gl, lp = compare(A, L)
        holds &= ga < gl and m >= -0.02
        print(f"    {s}: {ga:.0f} vs {gl:.0f} Gaussians ({100 * (1 - ga / gl):+.1f}% fewer), {m:+.3f} [{lo:+.3f}, "
              f"{hi:+.3f}] dB, LPIPS {lp:+.4f}")
    print("hypothesis", "holds" if holds else "does not hold")

# Issue 16's two targets for a round's choices on a fresh folder (both seeds averaged per pair, paired bootstrap 95%
# intervals), with the linear split merge at the same budget as a reference row, then the round's pruning choice
# against it. Usage: python3 targets.py <eval out folder> [srgb|flatness|flatness3|fresh4]
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '2026-11-27-merge-split'))
from targets import method, compare, report, root  # the split report's loader: reads sys.argv[1] as the folder

ROUNDS = {'srgb': [("pruning choice", 'full_merge2sr06', '0.85', '0.85', 'prune'),
                   ("2x choice", 'full_merge2sr03', '0.64', 'best', '2x')],
          'flatness': [("pruning choice", 'full_merge2sf03', '0.85', '0.85', 'prune'),
                       ("2x hypothesis", 'full_merge2sf04', '0.85', 'best', '2x'),
                       ("2x hypothesis, as pruning", 'full_merge2sf04', '0.85', '0.85', 'prune')],
          'fresh4': [("pruning choice", 'full_merge2sf03', '0.85', '0.85', 'prune')],
          'flatness3': [("2x choice", 'full_merge2sf03-px064', '0.64', 'best', '2x'),
                        ("2x choice, as pruning", 'full_merge2sf03-px064', '0.64', '0.85', 'prune')]}
rows = ROUNDS[sys.argv[2] if len(sys.argv) > 2 else 'srgb']
report(rows + [("linear split merge, for reference", 'full_merge2s', '0.85', '0.85', 'prune')])
chosen = rows[0][1]
if rows[0][2] != '0.85': sys.exit(0)  # the comparison below is for pruning choices at the recipe's budget
print(f"## the pruning choice against the linear split merge ({chosen[5:]}@px0.85 - merge2s@px0.85)")
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    m, lo, hi, ga, gl, lp = compare(method(s, chosen, '0.85'), method(s, 'full_merge2s', '0.85'))
    print(f"{s}: {ga:.0f} vs {gl:.0f} Gaussians ({100 * (1 - ga / gl):+.1f}% fewer), {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, "
          f"LPIPS {lp:+.4f}")

# Issue 16's two targets for the sRGB choices on a fresh folder (both seeds averaged per pair, paired bootstrap 95%
# intervals), with the linear test at the same budget as a reference row, then the sRGB pruning choice against it.
# Usage: python3 targets.py <eval out folder>
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '2026-11-27-merge-split'))
from targets import method, compare, report, root  # the split report's loader: reads sys.argv[1] as the folder

report([("pruning choice", 'full_merge2sr06', '0.85', '0.85', 'prune'),
        ("2x choice", 'full_merge2sr03', '0.64', 'best', '2x'),
        ("linear test, for reference", 'full_merge2s', '0.85', '0.85', 'prune')])
print("## sRGB pruning choice against the linear test (merge2sr06@px0.85 - merge2s@px0.85)")
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    m, lo, hi, ga, gl, lp = compare(method(s, 'full_merge2sr06', '0.85'), method(s, 'full_merge2s', '0.85'))
    print(f"{s}: {ga:.0f} vs {gl:.0f} Gaussians ({100 * (1 - ga / gl):+.1f}% fewer), {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, "
          f"LPIPS {lp:+.4f}")

# Where merging's count stops: per set and method, the means over pairs of pruning's logged counts (seed 0, px0.85).
# Usage: python3 counts.py <eval out folder>
import json, os, sys
root = sys.argv[1]
methods = [('linear, 0.03', 'full_merge2s-counts'), ('sRGB, 0.06', 'full_merge2sr06-counts'),
           ('sRGB, colour test off', 'full_merge2sr100-counts')]
print("| set | colour test | decoded | removed | alone | in merged groups | refused groups: colour / flatness / "
      "normals |")
print("|---|---|---|---|---|---|---|")
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    for label, m in methods:
        path = f"{root}/{s}/results_{m}_px0_85.jsonl"
        if not os.path.exists(path): continue
        rows = [json.loads(l) for l in open(path)]
        mean = lambda f: sum(f(r) for r in rows) / len(rows)
        dec = mean(lambda r: r['decoded'])
        pc = lambda k: mean(lambda r: r['prune'][k])
        removed = pc('merged_members') - pc('merged_groups')
        print(f"| {s} | {label} | {dec:.0f} | {100 * removed / dec:.1f}% | {100 * pc('alone') / dec:.1f}% | "
              f"{100 * pc('merged_members') / dec:.1f}% | {pc('refused_color'):.0f} / {pc('refused_shape'):.0f} / "
              f"{pc('refused_normal'):.0f} |")

# Ceiling of any per-image budget rule: each source image picks its own fixed budget (px:<b>) from the swept ones so
# that the mean count is smallest while mean PSNR stays within `tol` dB of the set's best fixed budget. Chosen on the
# very pairs it is scored on, so it is an upper bound, not a rule. Plain python3.
# Usage: python3 oracle.py <eval out folder> <method> [tol=0.1]   (reads results_<method>_px*.jsonl of every set)
import json, os, re, sys
root, method = sys.argv[1], sys.argv[2]
tol = float(sys.argv[3]) if len(sys.argv) > 3 else 0.1
pat = re.compile(re.escape(method) + r'_px(\d+)_(\d+)\.jsonl$')
for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
    pairs = json.load(open(f"{root}/{s}/manifest.json"))['pairs']
    runs = {}
    for f in os.listdir(f"{root}/{s}"):
        m = pat.match(f[len('results_'):]) if f.startswith('results_') else None
        if m:
            runs[float(f"{m.group(1)}.{m.group(2)}")] = {r['index']: r for r in map(json.loads, open(f"{root}/{s}/{f}"))}
    if not runs:
        continue
    keys = sorted(set.intersection(*(set(r) for r in runs.values())))
    budgets = sorted(runs)
    mean = lambda b, f: sum(runs[b][k][f] for k in keys) / len(keys)
    best = max(budgets, key=lambda b: mean(b, 'psnr'))
    goal = mean(best, 'psnr') - tol
    by_source = {}
    for k in keys:
        by_source.setdefault(pairs[k]['source'], []).append(k)
    # Lagrangian sweep: each source minimizes count - lam * psnr (summed over its pairs); keep the cheapest choice
    # whose mean PSNR meets the goal.
    found = None
    for step in range(0, 4001):
        lam = 10.0 * 1.003 ** step
        psnr = count = 0.0
        pick = {}
        for src, ks in by_source.items():
            b = min(budgets, key=lambda b: sum(runs[b][k]['gaussians'] - lam * runs[b][k]['psnr'] for k in ks))
            pick[src] = b
            psnr += sum(runs[b][k]['psnr'] for k in ks)
            count += sum(runs[b][k]['gaussians'] for k in ks)
        if psnr / len(keys) >= goal:
            found = (count / len(keys), psnr / len(keys), pick)
            break
    fixed = ', '.join(f"px{b:g} {mean(b, 'psnr'):.2f} dB {mean(b, 'gaussians') / 1000:.1f}k" for b in budgets)
    print(f"{s}: {len(keys)} pairs, {len(by_source)} source images; fixed: {fixed}")
    if found:
        c, p, pick = found
        hist = {b: sum(1 for v in pick.values() if v == b) for b in budgets}
        print(f"  best fixed px{best:g}: {mean(best, 'psnr'):.2f} dB at {mean(best, 'gaussians') / 1000:.1f}k; oracle per image: "
              f"{p:.2f} dB at {c / 1000:.1f}k = {mean(best, 'gaussians') / c:.2f}x fewer; images per budget "
              + ', '.join(f"px{b:g}: {n}" for b, n in hist.items()))

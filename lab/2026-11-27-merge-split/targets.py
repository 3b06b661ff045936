# Issue 16's two targets for the chosen settings on an evaluation folder, with both seeds averaged per pair and paired
# bootstrap 95% intervals (2000 resamples, seed 0), overall and per bin. Usage: python3 targets.py <eval out folder>
# [selection|confirm|confirm2]: the development choices (and split alone) on the selection sets, or the hypotheses on fresh ones.
import json, os, random, sys
root = sys.argv[1]
def load(s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
def method(s, name, budget):  # two seeds: name@budget and name_s1@budget, averaged per pair
    b = budget.replace('.', '_')
    runs = [load(s, f"{name}_px{b}"), load(s, f"{name}_s1_px{b}")]
    keys = [k for k in runs[0] if k in runs[1]]
    fields = ('psnr', 'gaussians', 'lpips_squeeze', 'bin')
    return {k: {f: (runs[0][k][f] if f == 'bin' else sum(r[k][f] for r in runs) / 2) for f in fields} for k in keys}
def interval(d):
    rng = random.Random(0)
    bs = sorted(sum(rng.choice(d) for _ in d) / len(d) for _ in range(2000))
    return sum(d) / len(d), bs[50], bs[1949]
def compare(A, B, bin=None):
    keys = sorted(k for k in A if k in B and (bin is None or A[k]['bin'] == bin))
    m, lo, hi = interval([A[k]['psnr'] - B[k]['psnr'] for k in keys])
    lp = sum(A[k]['lpips_squeeze'] - B[k]['lpips_squeeze'] for k in keys) / len(keys)
    ga = sum(A[k]['gaussians'] for k in keys) / len(keys)
    gb = sum(B[k]['gaussians'] for k in keys) / len(keys)
    return m, lo, hi, ga, gb, lp
budgets = ['0.43', '0.64', '0.85']
# (label, method file stem, budget, reference: a budget or 'best', target kind)
ROWS = {
    'selection': [("pruning choice", 'full_merge2sL2', '0.64', '0.85', 'prune'),
                  ("2x choice", 'full_merge2sL2', '0.43', 'best', '2x'),
                  ("not chosen: split alone at the recipe's budget", 'full_merge2s', '0.85', '0.85', 'prune')],
    'confirm': [("pruning hypothesis", 'full_merge2s', '0.85', '0.85', 'prune'),
                ("2x hypothesis", 'full_merge2s-budgets', '0.64', 'best', '2x')],
    'confirm2': [("pruning hypothesis, second fresh sets", 'full_merge2s', '0.85', '0.85', 'prune'),
                 ("second 2x hypothesis", 'full_merge2s-px053', '0.53', 'best', '2x')],
}
def report(rows):
    for s in sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}")):
        fixed = {b: method(s, 'full', b) for b in budgets}
        mean = lambda M: sum(v['psnr'] for v in M.values()) / len(M)
        best = max(budgets, key=lambda b: mean(fixed[b]))
        bins = sorted({v['bin'] for v in fixed['0.85'].values()})
        print(f"## {s}: fixed budgets (two seeds) " + ", ".join(f"px{b} {mean(fixed[b]):.2f} dB" for b in budgets)
              + f"; best px{best}")
        for label, name, b, ref, kind in rows:
            ref = best if ref == 'best' else ref
            M = method(s, name, b)
            m, lo, hi, ga, gr, lp = compare(M, fixed[ref])
            if kind == 'prune':
                saving, met = f"{100 * (1 - ga / gr):.1f}% fewer", ga <= 0.7 * gr and m >= -0.05
            else:
                saving, met = f"{gr / ga:.2f}x fewer", 2 * ga <= gr and m >= -0.1
            short = name.replace('full_', '').replace('-budgets', '')
            print(f"{label}: {short}@px{b} vs px{ref}: {ga:.0f} vs {gr:.0f} Gaussians, {saving}, "
                  f"PSNR {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, LPIPS {lp:+.4f}: {'met' if met else 'missed'}")
            for bn in bins:
                m, lo, hi, _, _, lp = compare(M, fixed[ref], bn)
                print(f"    bin {bn}: {m:+.3f} [{lo:+.3f}, {hi:+.3f}] dB, LPIPS {lp:+.4f}")

if __name__ == '__main__':
    report(ROWS[sys.argv[2] if len(sys.argv) > 2 else 'selection'])

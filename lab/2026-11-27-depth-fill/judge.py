# The depth-fill hypotheses on the evaluation sets, by the rule in ../2026-11-27-depth-fill.md: both seeds of
# `full` averaged per pair, with and without the chosen fill, at each share of depth holes.
# Usage: python3 judge.py <eval out folder> <fill name, e.g. fill32>
import json, os, random, sys
root, fill = sys.argv[1], sys.argv[2]
LEVELS = ["0", "0_1", "0_3", "0_5"]
def load_one(s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
def load(s, names):  # per-pair mean over seeds
    runs = [load_one(s, m) for m in names]
    keys = [k for k in runs[0] if all(k in r for r in runs)]
    out = {}
    for k in keys:
        row = {'bin': runs[0][k]['bin']}
        for f in ('psnr', 'hole_rate', 'crack_rate', 'lpips_squeeze'):
            v = [r[k].get(f) for r in runs]
            row[f] = None if None in v else sum(v) / len(v)
        out[k] = row
    return out
def mean(a, f='psnr', scale=1):
    v = [scale * r[f] for r in a.values() if r[f] is not None]
    return sum(v) / len(v)
def paired(a, b, f='psnr', scale=1):
    ks = [k for k in a if k in b and a[k][f] is not None and b[k][f] is not None]
    d = [scale * (a[k][f] - b[k][f]) for k in ks]
    rng = random.Random(0)
    bs = sorted(sum(d[rng.randrange(len(d))] for _ in d) / len(d) for _ in range(2000))
    return sum(d) / len(d), bs[50], bs[1949]
fmt = lambda t: f"{t[0]:+.2f} [{t[1]:+.2f}, {t[2]:+.2f}]"
sets = sorted(d for d in os.listdir(root) if os.path.exists(f"{root}/{d}/results_full_depth_holes0.jsonl"))
verdict = {1: True, 2: True, 3: True}
for s in sets:
    plain = {h: load(s, [f"full_depth_holes{h}", f"full_s1_depth_holes{h}"]) for h in LEVELS}
    filled = {h: load(s, [f"full_{fill}_depth_holes{h}", f"full_{fill}_s1_depth_holes{h}"]) for h in LEVELS}
    clean = mean(plain["0"])
    print(f"== {s} ({len(plain['0'])} pairs)")
    print("  holes:            " + " | ".join(f"{h.replace('_', '.'):>5}" for h in LEVELS))
    print("  PSNR, no fill:    " + " | ".join(f"{mean(plain[h]):5.2f}" for h in LEVELS))
    print("  PSNR, fill:       " + " | ".join(f"{mean(filled[h]):5.2f}" for h in LEVELS))
    print("  holes %, no fill: " + " | ".join(f"{mean(plain[h], 'hole_rate', 100):5.2f}" for h in LEVELS))
    print("  holes %, fill:    " + " | ".join(f"{mean(filled[h], 'hole_rate', 100):5.2f}" for h in LEVELS))
    print("  cracks %, no fill:" + " | ".join(f"{mean(plain[h], 'crack_rate', 100):5.2f}" for h in LEVELS))
    print("  cracks %, fill:   " + " | ".join(f"{mean(filled[h], 'crack_rate', 100):5.2f}" for h in LEVELS))
    for h in LEVELS:
        d = paired(filled[h], plain[h])
        line = f"  fill - no fill at {h.replace('_', '.')}: PSNR {fmt(d)}, LPIPS {paired(filled[h], plain[h], 'lpips_squeeze')[0]:+.3f}"
        line += ", per bin " + " / ".join(
            fmt(paired({k: r for k, r in filled[h].items() if r['bin'] == b},
                       {k: r for k, r in plain[h].items() if r['bin'] == b})) for b in range(4))
        if h != "0":
            lost = clean - mean(plain[h])
            won = mean(filled[h]) - mean(plain[h])
            line += f"; wins back {won:.2f} of {lost:.2f} dB ({100 * won / lost:.0f}%)"
            if h in ("0_1", "0_3") and won < 0.5 * lost:
                verdict[1] = False
        else:
            if d[0] < -0.05:
                verdict[2] = False
        print(line)
    hu, hf = mean(plain["0_3"], 'hole_rate', 100), mean(filled["0_3"], 'hole_rate', 100)
    print(f"  hole rate at 30%: {hu:.2f} -> {hf:.2f} % ({'halved' if hf <= 0.5 * hu else 'NOT halved'})")
    if hf > 0.5 * hu:
        verdict[3] = False
print("hypotheses (every set):", ", ".join(f"{k}: {'holds' if v else 'fails'}" for k, v in verdict.items()))

# The depth-fill choice on the development scenes, by the rule in ../2026-11-27-depth-fill.md.
# Usage: python3 choose.py <eval out folder> (e.g. out/experiments/fill_dev)
import json, os, random, sys
root = sys.argv[1]
sets = sorted(d for d in os.listdir(root) if os.path.isdir(f"{root}/{d}"))
def load(s, m):
    return {r['index']: r for r in map(json.loads, open(f"{root}/{s}/results_{m}.jsonl"))}
def paired(a, b, f='psnr', scale=1):
    ks = [k for k in a if k in b and a[k].get(f) is not None and b[k].get(f) is not None]
    d = [scale * (a[k][f] - b[k][f]) for k in ks]
    rng = random.Random(0)
    bs = sorted(sum(d[rng.randrange(len(d))] for _ in d) / len(d) for _ in range(2000))
    return sum(d) / len(d), bs[50], bs[1949]
def mean(a, f='psnr', scale=1):
    v = [scale * r[f] for r in a.values() if r.get(f) is not None]
    return sum(v) / len(v)
for s in sets:
    print(f"== {s}")
    base = {h: load(s, f"full_depth_holes{h}") for h in ("0", "0_1", "0_3")}
    print("no fill: PSNR at 0/10/30% holes", " / ".join(f"{mean(base[h]):.2f}" for h in base),
          "| holes %", " / ".join(f"{mean(base[h], 'hole_rate', 100):.2f}" for h in base))
    rows = []
    for n in (4, 8, 16, 32):
        run = {h: load(s, f"full_fill{n}_depth_holes{h}") for h in base}
        d0 = paired(run["0"], base["0"])
        score = (mean(run["0_1"]) + mean(run["0_3"])) / 2
        eligible = d0[0] >= -0.05
        rows.append((n, score, eligible))
        print(f"fill {n:2d}: PSNR " + " / ".join(f"{mean(run[h]):.2f}" for h in run)
              + f" | at 0%: {d0[0]:+.3f} [{d0[1]:+.3f}, {d0[2]:+.3f}] {'eligible' if eligible else 'NOT eligible'}"
              + " | vs no fill at 10/30%: " + " / ".join("{:+.2f} [{:+.2f}, {:+.2f}]".format(*paired(run[h], base[h])) for h in ("0_1", "0_3"))
              + " | holes % " + " / ".join(f"{mean(run[h], 'hole_rate', 100):.2f}" for h in run)
              + f" | mean of 10/30%: {score:.3f}")
    ok = [r for r in rows if r[2]]
    if not ok:
        print("choice: none eligible")
        continue
    best = max(r[1] for r in ok)
    chosen = min(r[0] for r in ok if r[1] >= best - 0.05)
    print(f"choice: fill_px = {chosen} (best mean {best:.3f}; ties within 0.05 dB go to the smallest)")

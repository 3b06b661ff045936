#!/usr/bin/env python3
"""The study's pre-registered rule applied to a candidate fix (README, "The rule for a fix"), per dataset:
LPIPS against the better pixel-aligned row (paired interval not above 0: its lower end at or below 0), PSNR against `full` (no lower by more
than 0.05 dB) and holes in the largest baseline bin against `full` (no higher by more than 0.02 points).
Paired over pairs and both seeds, cluster-bootstrap 95% intervals over pairs.

Usage: python3 lab/2026-12-06-lpips-gap/rule.py EVAL_DIR CANDIDATE [DATASET ...]   (prints a Markdown table)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from regions import SEEDS, interval, results  # noqa: E402

PIXEL_ROWS = ["pixel_supports", "dense_decoder"]


def paired(a_logs, b_logs, field, keep=lambda r: True):
    diffs = {}
    for s in SEEDS:
        a, b = a_logs[s], b_logs[s]
        for i in a.keys() & b.keys():
            x, y = a[i].get(field), b[i].get(field)
            if keep(a[i]) and x is not None and y is not None:
                diffs.setdefault(i, []).append(x - y)
    return interval(diffs)


def mean(logs, field):
    v = [r[field] for s in SEEDS for r in logs[s].values() if r.get(field) is not None]
    return sum(v) / len(v)


def fmt(iv, digits, scale=1.0):
    return f"{iv[0] * scale:+.{digits}f} [{iv[1] * scale:+.{digits}f}, {iv[2] * scale:+.{digits}f}]"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    eval_dir, candidate = sys.argv[1], sys.argv[2]
    datasets = sys.argv[3:] or sorted(
        d for d in os.listdir(eval_dir) if os.path.isfile(os.path.join(eval_dir, d, "manifest.json")))
    print(f"| dataset | LPIPS − better pixel row | PSNR − full (dB) | holes − full, largest bin (points) | passes |")
    print("|---|---|---|---|---|")
    for d in datasets:
        logs = {row: {s: results(eval_dir, d, row, s) for s in SEEDS} for row in ["full", candidate] + PIXEL_ROWS}
        best = min(PIXEL_ROWS, key=lambda row: mean(logs[row], "lpips_squeeze"))
        lp = paired(logs[candidate], logs[best], "lpips_squeeze")
        ps = paired(logs[candidate], logs["full"], "psnr")
        last = max(r["bin"] for r in logs["full"][0].values())
        holes = paired(logs[candidate], logs["full"], "hole_rate", keep=lambda r: r["bin"] == last)
        ok = lp[1] <= 0 and ps[0] >= -0.05 and holes[0] * 100 <= 0.02  # "not above 0": not wholly above
        print(f"| {d} | {fmt(lp, 4)} ({best}) | {fmt(ps, 2)} | {fmt(holes, 3, 100)} | {'yes' if ok else 'no'} |")


if __name__ == "__main__":
    main()

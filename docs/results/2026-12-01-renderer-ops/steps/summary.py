#!/usr/bin/env python3
"""Per case and phase: ranges of two named binaries and the median of the paired (same round) differences. Usage: summary.py A B FILE..."""
import re
import sys
from pathlib import Path

COLS = ["case", "N", "image", "visible", "isects", "first", "fwd", "fb", "Misect", "proj", "bin", "rast", "rbwd", "pbwd"]
PHASES = ["fwd", "fb", "proj", "bin", "rast", "rbwd", "pbwd"]


def parse(path):
    rows, current = {}, None
    for line in Path(path).read_text().splitlines():
        m = re.match(r"## round (\d+) (\w+)", line)
        if m:
            current = (int(m.group(1)), m.group(2))
        elif line.startswith("|"):
            rows.setdefault(current, []).append([x.strip() for x in line.strip().strip("|").split("|")])
    return rows


def median(xs):
    xs = sorted(xs)
    k = len(xs) // 2
    return xs[k] if len(xs) % 2 else (xs[k - 1] + xs[k]) / 2


for path in sys.argv[3:]:
    rows = parse(path)
    for case in dict.fromkeys(r[0] for (_, _), v in sorted(rows.items()) for r in v):
        for col in PHASES:
            i = COLS.index(col)
            pick = lambda b: [float(r[i]) for (k, bb), v in sorted(rows.items()) if bb == b for r in v if r[0] == case]
            old, new = pick(sys.argv[1]), pick(sys.argv[2])
            d = [n - o for o, n in zip(old, new)]
            print(f"{Path(path).stem:22s} {case:18s} {col:5s} old {min(old):6.1f}-{max(old):6.1f}  "
                  f"new {min(new):6.1f}-{max(new):6.1f}  new-old median {median(d):+6.2f} ({min(d):+.1f} to {max(d):+.1f})")

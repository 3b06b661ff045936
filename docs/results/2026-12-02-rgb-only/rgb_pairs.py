#!/usr/bin/env python3
"""Forward + backward of the colour-only pass against the full one, per case, from bench/rounds.sh files whose NEW
binary has the last column (f+b rgb). Prints ranges and the median of the paired differences per round:
new f+b rgb - old f+b (the binaries compared) and new f+b rgb - new f+b (the same process).
Usage: rgb_pairs.py FILE..."""
import re
import sys
from pathlib import Path

FB, FBRGB = 7, 22  # column indices in bench_render's table rows


def median(xs):
    xs = sorted(xs)
    k = len(xs) // 2
    return xs[k] if len(xs) % 2 else (xs[k - 1] + xs[k]) / 2


for path in sys.argv[1:]:
    rows, current = {}, None
    for line in Path(path).read_text().splitlines():
        m = re.match(r"## round (\d+) (\w+)", line)
        if m:
            current = (int(m.group(1)), m.group(2))
        elif line.startswith("|"):
            r = [x.strip() for x in line.strip().strip("|").split("|")]
            rows[(current[0], current[1], r[0])] = r
    cases = dict.fromkeys(k[2] for k in rows)
    rounds = sorted({k[0] for k in rows})
    for case in cases:
        old_fb = [float(rows[(n, "old", case)][FB]) for n in rounds]
        new_fb = [float(rows[(n, "new", case)][FB]) for n in rounds]
        new_rgb = [float(rows[(n, "new", case)][FBRGB]) for n in rounds]
        d_old = [a - b for a, b in zip(new_rgb, old_fb)]
        d_new = [a - b for a, b in zip(new_rgb, new_fb)]
        under40 = sum(x < 40 for x in new_rgb), sum(x < 40 for x in old_fb)
        print(f"{Path(path).stem:14s} {case:18s} old f+b {min(old_fb):5.1f}-{max(old_fb):5.1f}  "
              f"new f+b {min(new_fb):5.1f}-{max(new_fb):5.1f}  new f+b rgb {min(new_rgb):5.1f}-{max(new_rgb):5.1f}  "
              f"rgb-old median {median(d_old):+5.2f}  rgb-new median {median(d_new):+5.2f}  "
              f"rounds under 40: rgb {under40[0]}/{len(rounds)}, old {under40[1]}/{len(rounds)}")

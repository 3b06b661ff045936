#!/usr/bin/env python3
"""Forward + backward of the colour-only pass against the full one, per case, from bench/rounds.sh files whose NEW
binary has the last column (f+b rgb). Prints ranges and the median of the paired differences per round:
new f+b rgb - old f+b (the binaries compared) and new f+b rgb - new f+b (the same process).
Usage: rgb_pairs.py FILE..."""
import sys
from pathlib import Path

# The round-file parser, median and column names of the phase summary (bench/rounds_summary.py).
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from rounds_summary import COLS, median, parse  # noqa: E402

FB, FBRGB = COLS.index("fb"), COLS.index("fbrgb")

for path in sys.argv[1:]:
    rows = {(n, binary, r[0]): r for (n, binary), v in parse(path).items() for r in v}
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

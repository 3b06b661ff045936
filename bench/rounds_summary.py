#!/usr/bin/env python3
"""Per case and phase: the old and new ranges and the median of the paired (same round) differences, new - old.
Usage: bench/rounds_summary.py [--names OLD NEW] FILE... (the files bench/rounds.sh writes); --names compares two other binaries of the rounds (default old, new)."""
import re
import sys
from pathlib import Path

COLS = ["case", "N", "image", "visible", "isects", "first", "fwd", "fb", "Misect", "proj", "bin", "rast", "rbwd", "pbwd",
        "peakF", "peakFB", "rss0", "bufF", "bufB", "build", "cpuF", "cpuB", "fbrgb", "fwdmed"]
# fbrgb, fwdmed: only in rows that have them (2026-12-02)
PHASES = ["fwd", "fb", "proj", "bin", "rast", "rbwd", "pbwd", "fbrgb", "fwdmed"]


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


def main(args):
    names = ("old", "new")
    if args[:1] == ["--names"]:
        names, args = (args[1], args[2]), args[3:]
    for path in args:
        rows = parse(path)
        for case in dict.fromkeys(r[0] for (_, _), v in sorted(rows.items()) for r in v):
            for col in PHASES:
                i = COLS.index(col)
                pick = lambda b: [float(r[i]) for (k, bb), v in sorted(rows.items()) if bb == b for r in v
                                  if r[0] == case and len(r) > i]
                old, new = pick(names[0]), pick(names[1])
                if not old or not new:
                    continue
                d = [n - o for o, n in zip(old, new)]
                print(f"{Path(path).stem:22s} {case:18s} {col:5s} old {min(old):6.1f}-{max(old):6.1f}  "
                      f"new {min(new):6.1f}-{max(new):6.1f}  new-old median {median(d):+6.2f} "
                      f"({min(d):+.1f} to {max(d):+.1f})")


if __name__ == "__main__":  # importable: other scripts reuse parse, median and COLS
    main(sys.argv[1:])

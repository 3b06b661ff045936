#!/usr/bin/env python3
"""Ranges per build and the median of the paired (same round) differences B - A, for bench_predict's stages and
bench_train_step's phases, from a file rounds.sh (or the env_* scripts) wrote. Usage: summary.py FILE NAME_A NAME_B"""
import re
import sys
from pathlib import Path


def parse(path):
    """{(round, name, kind): {key: ms}}; kind is predict100k, predict40k or train."""
    rows, cur = {}, None
    for line in Path(path).read_text().splitlines():
        m = re.match(r"## round (\d+) (\S+)(?: (predict|train))?", line)
        if m:
            cur = (int(m.group(1)), m.group(2), m.group(3) or "")
            continue
        if cur is None:
            continue
        r, name, kind = cur
        if line.startswith(("quickstart", "ViT-S, 40k")):
            sub = "predict100k" if line.startswith("quickstart") else "predict40k"
            vals = dict((k, float(v)) for k, v in re.findall(r"(sampler|encoder|decoder|composer|total) +([0-9.]+)", line))
            rows[(r, name, sub)] = vals
            last = sub
        elif line.strip().startswith("decoder parts"):
            m2 = re.search(r"fused query and gate +([0-9.]+) ms, MLP\+head +([0-9.]+)", line)
            rows[(r, name, last)].update({"fused": float(m2.group(1)), "mlp": float(m2.group(2))})
        else:
            m2 = re.match(r"^  ([a-z_]+) +([0-9.]+)$", line)
            if m2:
                rows.setdefault((r, name, "train"), {})[m2.group(1)] = float(m2.group(2))
    return rows


def median(xs):
    xs = sorted(xs)
    k = len(xs) // 2
    return xs[k] if len(xs) % 2 else (xs[k - 1] + xs[k]) / 2


def main(path, a, b):
    rows = parse(path)
    rounds = sorted({r for r, _, _ in rows})
    for kind in ("predict100k", "predict40k", "train"):
        keys = sorted({k for (r, n, kd), v in rows.items() if kd == kind for k in v})
        for key in keys:
            get = lambda n: {r: rows[(r, n, kind)][key] for r in rounds if key in rows.get((r, n, kind), {})}
            va, vb = get(a), get(b)
            paired = [vb[r] - va[r] for r in rounds if r in va and r in vb]
            if not paired:
                continue
            print(f"{kind:12s} {key:11s} {a} {min(va.values()):7.1f}-{max(va.values()):7.1f}  "
                  f"{b} {min(vb.values()):7.1f}-{max(vb.values()):7.1f}  {b}-{a} median {median(paired):+8.1f} "
                  f"({min(paired):+.1f} to {max(paired):+.1f}, {len(paired)} rounds)")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])

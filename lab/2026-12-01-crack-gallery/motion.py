#!/usr/bin/env python3
"""Cracks at one baseline bin split by motion type (lateral, forward, rotation) and by side, a method minus a reference.

The farther part is the default measure minus the nearer one (scoring.crack_side = nearer) on the same pairs.
Intervals: seed-aware paired bootstrap (seed k of a against seed k of b, then pairs; 2000 resamples, 95%).

usage: motion.py <any dir> <nearer dir> <bin> <seeds, e.g. 0,1> <a> <b>
  a, b: results names with {k} for the seed (e.g. full-s{k} reads results_full-s0.jsonl ...)."""
import importlib.util
import json
import sys
from pathlib import Path

# seed_interval(d, seeds, n): the seed-aware bootstrap of lab/2026-11-28-seeds/seeds.py.
_spec = importlib.util.spec_from_file_location("seeds", Path(__file__).resolve().parent.parent / "2026-11-28-seeds" / "seeds.py")
seeds_py = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(seeds_py)



def load(folder, name):
    (path,) = Path(folder).rglob(f"results_{name}.jsonl")
    return {r["index"]: r for r in map(json.loads, path.read_text().splitlines())}


def main():
    any_dir, near_dir, b, seeds, a, ref = sys.argv[1:7]
    seeds = [int(s) for s in seeds.split(",")]
    parts = {}
    for name in (a, ref):
        for k in seeds:
            full, near = load(any_dir, name.format(k=k)), load(near_dir, name.format(k=k))
            parts[name, k] = {
                i: (r["motion"], 100 * r["crack_rate"], 100 * near[i]["crack_rate"])
                for i, r in full.items()
                if r["bin"] == int(b) and r.get("crack_rate") is not None and near[i].get("crack_rate") is not None
            }
    pairs = sorted(set.intersection(*(set(p) for p in parts.values())))
    for motion in ("lateral", "forward", "rotation", "all"):
        mine = [i for i in pairs if motion == "all" or parts[a, seeds[0]][i][0] == motion]
        if not mine:
            print(f"{motion}: no pairs")
            continue
        line = [f"{motion} ({len(mine)} pairs)"]
        for label, f in (("cracks", lambda v: v[1]), ("nearer", lambda v: v[2]), ("farther", lambda v: v[1] - v[2])):
            mean = lambda name: sum(f(parts[name, k][i]) for k in seeds for i in mine) / (len(seeds) * len(mine))
            d = {k: [f(parts[a, k][i]) - f(parts[ref, k][i]) for i in mine] for k in seeds}
            lo, hi = seeds_py.seed_interval(d, seeds, len(mine))
            line.append(f"{label} {mean(a):.3f} vs {mean(ref):.3f}: {mean(a) - mean(ref):+.3f} [{lo:+.3f}, {hi:+.3f}]")
        print(" | ".join(line))


if __name__ == "__main__":
    main()

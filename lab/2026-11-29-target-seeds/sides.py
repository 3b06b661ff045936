#!/usr/bin/env python3
"""Nearer and farther parts of the cracks in one baseline bin, each method minus a reference, seed-aware.

The farther part is the default measure minus the nearer one (`scoring.crack_side = nearer`) on the same pairs. The
interval draws seeds with replacement (seed k of a method against seed k of the reference), then pairs, 2000
resamples, 95% (seed_interval of lab/2026-11-28-seeds/seeds.py).

usage: sides.py <any dir> <nearer dir> <bin> <seeds, e.g. 0,1,2,3> <label=any_name,nearer_name> ...
  names are results files without "results_" and ".jsonl", with {s} for the seed; the first method is the reference.
"""
import importlib.util
import json
import os
import sys

_spec = importlib.util.spec_from_file_location(
    "seeds", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-11-28-seeds", "seeds.py"))
seeds_py = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(seeds_py)

any_dir, nearer_dir, bin_index = sys.argv[1], sys.argv[2], int(sys.argv[3])
seeds = [int(x) for x in sys.argv[4].split(",")]
methods = [(m.split("=")[0], m.split("=")[1].split(",")) for m in sys.argv[5:]]


def load(path):
    return {r["index"]: r for r in map(json.loads, open(path))}


def parts(names, seed):
    a = load(f"{any_dir}/results_{names[0].format(s=seed)}.jsonl")
    n = load(f"{nearer_dir}/results_{names[1].format(s=seed)}.jsonl")
    return {i: (100 * r["crack_rate"], 100 * n[i]["crack_rate"], 100 * (r["crack_rate"] - n[i]["crack_rate"]))
            for i, r in a.items() if r["bin"] == bin_index and r.get("crack_rate") is not None}


P = {(label, s): parts(names, s) for label, names in methods for s in seeds}
ref = methods[0][0]
keys = sorted(set.intersection(*(set(v) for v in P.values())))
for label, _ in methods:
    m = [sum(P[(label, s)][i][k] for s in seeds for i in keys) / (len(seeds) * len(keys)) for k in range(3)]
    print(f"{label}: cracks {m[0]:.3f} nearer {m[1]:.3f} farther {m[2]:.3f}  ({len(keys)} pairs, {len(seeds)} seeds)")
for label, _ in methods[1:]:
    txt = []
    for k, name in enumerate(("cracks", "nearer", "farther")):
        d = {s: [P[(label, s)][i][k] - P[(ref, s)][i][k] for i in keys] for s in seeds}
        per = [sum(d[s]) / len(keys) for s in seeds]
        lo, hi = seeds_py.seed_interval(d, seeds, len(keys))
        txt.append(f"{name} {sum(per) / len(seeds):+.3f} [{lo:+.3f}, {hi:+.3f}] "
                   f"(seeds {' '.join(f'{x:+.3f}' for x in per)})")
    print(f"{label} - {ref}:", " | ".join(txt))

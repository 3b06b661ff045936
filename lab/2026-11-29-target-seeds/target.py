#!/usr/bin/env python3
"""Issue 17's target from an experiment report.json: each pixel row minus `full` at the last baseline bin, seed-aware.

usage: target.py out/experiments/ablation/report.json [variant]
"""
import json
import sys

rows = json.load(open(sys.argv[1]))
variant = sys.argv[2] if len(sys.argv) > 2 else "depth"


def interval(r, key):
    # [lo, hi]: report.json's delta_<key>_lo and _hi (reports before the one table writer: delta_<key>_ci)
    return [r[f"{key}_lo"], r[f"{key}_hi"]] if f"{key}_lo" in r else r.get(f"{key}_ci")


def verdict(lo, hi):
    # the row minus full: above 0 means full has fewer, the target
    return "met" if lo > 0 else "not met" if hi < 0 else "level"


for ds in dict.fromkeys(r["dataset"] for r in rows):
    mine = [r for r in rows if r["dataset"] == ds and r["variant"] == variant]
    last = [r["bin"] for r in mine if r["bin"] != "all"][-1]
    print(f"## {ds}, bin {last}")
    for r in mine:
        if r["bin"] not in ("all", last) or not r["row"].startswith(("pixel_supports", "dense_decoder", "full")):
            continue
        cells = [r["row"], r["bin"], r["interval"], f"pairs {r['pairs']}", f"psnr {r['psnr']:.2f}" if r["psnr"] is not None else "psnr n/a"]
        for key in ("holes", "cracks"):
            v, ci = r.get(f"delta_{key}"), interval(r, f"delta_{key}")
            pct = r.get(f"{key}_pct")
            txt = f"{key} {pct:.3f}" if pct is not None else f"{key} n/a"
            if v is not None and ci and None not in ci:
                txt += f" d {v:+.3f} [{ci[0]:+.3f}, {ci[1]:+.3f}]"
                if r["bin"] == last and "seeds" in r["row"]:
                    txt += " " + verdict(ci[0], ci[1])
            cells.append(txt)
        if r["delta_psnr"] is not None and interval(r, "delta_psnr"):
            ci = interval(r, "delta_psnr")
            cells.append(f"dpsnr {r['delta_psnr']:+.2f} [{ci[0]:+.2f}, {ci[1]:+.2f}]")
        print(" | ".join(cells))
    print()

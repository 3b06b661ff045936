#!/usr/bin/env python3
"""Mean crack and hole rates (points) and PSNR per row at one bin of the atria, averaged over seeds.

usage: rates.py <eval out folder> <bin> <rows, e.g. full,dense_decoder> <seeds, e.g. 0,1,2,3>"""
import json, sys, statistics
root, b = sys.argv[1], int(sys.argv[2])
for row in sys.argv[3].split(","):
    vals = {"crack_rate": [], "hole_rate": [], "psnr": []}
    seeds = [int(s) for s in sys.argv[4].split(",")]
    for k in seeds:
        try:
            rs = [json.loads(l) for l in open(f"{root}/atrium-nerfstudio/results_{row}-s{k}.jsonl")]
        except FileNotFoundError:
            continue
        rs = [r for r in rs if r["bin"] == b]
        for f in vals:
            xs = [r[f] for r in rs if r.get(f) is not None]
            vals[f].append(sum(xs) / len(xs))
    if vals["psnr"]:
        print(row, len(vals["psnr"]), "seeds", "cracks %.3f" % (100 * statistics.mean(vals["crack_rate"])), "holes %.3f" % (100 * statistics.mean(vals["hole_rate"])), "psnr %.2f" % statistics.mean(vals["psnr"]))

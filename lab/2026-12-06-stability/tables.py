#!/usr/bin/env python3
"""The stability report's tables from the evaluator's outputs: sweep slopes per row (slopes.csv), and the rows' holes and
cracks at the largest baselines with paired differences to the full model (report.json, differences.csv).

Usage: tables.py STABILITY_OUT FAILURES_OUT
"""
import csv
import json
import os
import sys

ROWS = ["full", "pixel_supports", "dense_decoder", "lift"]


def slopes(out):
    table = {}
    for r in csv.DictReader(open(os.path.join(out, "slopes.csv"))):
        method, key = r["sweep"].split(" ", 1)
        table.setdefault((r["dataset"], key), {})[method] = r
    print("| set | sweep | unit | " + " | ".join(ROWS + ["lidar"]) + " |")
    print("|---|---|---|" + "---|" * (len(ROWS) + 1))
    for (dataset, key), by in sorted(table.items()):
        unit = next(iter(by.values()))["unit"]
        cells = []
        for m in ROWS + ["lidar"]:
            r = by.get(m)
            cells.append(f"{float(r['slope_db']):+.3f} [{float(r['slope_lo']):+.3f}, {float(r['slope_hi']):+.3f}]"
                         if r else "")
        print(f"| {dataset} | {key} | dB per {unit} | " + " | ".join(cells) + " |")


def rows_at_largest(out):
    report = json.load(open(os.path.join(out, "report.json")))
    # Sweep points share their method's name and carry sweep_value (empty or absent for the rows themselves).
    diffs = {(r["dataset"], r["method"], r["bin"]): r for r in csv.DictReader(open(os.path.join(out, "differences.csv")))
             if not r.get("sweep_value")}
    print("| set | method | pairs | PSNR all bins | holes % at [2,inf) | cracks % at [2,inf) | row - full: PSNR dB (all) | "
          "holes pp at [2,inf) | cracks pp at [2,inf) |")
    print("|---|---|---|---|---|---|---|---|---|")
    by = {(r["dataset"], r["method"], r["bin"]): r for r in report if r.get("sweep_value") is None}
    for dataset in sorted({r["dataset"] for r in report}):
        for m in ROWS:
            a, w = by.get((dataset, m, "all")), by.get((dataset, m, "[2,inf)"))
            if not a or not w:
                continue
            d_all, d_w = diffs.get((dataset, m, "all")), diffs.get((dataset, m, "[2,inf)"))
            iv = lambda d, k, s: f"{float(d[k + s[0]]):+.2f} [{float(d[k + s[1]]):+.2f}, {float(d[k + s[2]]):+.2f}]" if d else "-"
            print(f"| {dataset} | {m} | {a['pairs']} | {a['psnr']:.2f} | {100 * w['hole_rate']:.2f} | {100 * w['crack_rate']:.2f} | "
                  f"{iv(d_all, 'psnr', ('_diff', '_lo', '_hi'))} | {iv(d_w, 'holes', ('_pp', '_lo', '_hi'))} | "
                  f"{iv(d_w, 'cracks', ('_pp', '_lo', '_hi'))} |")


if __name__ == "__main__":
    print("## Sweep slopes (mean of per-pair slopes, 95% interval over pairs)\n")
    slopes(sys.argv[1])
    print("\n## The rows unperturbed, against the full model on the same pairs\n")
    rows_at_largest(sys.argv[2])

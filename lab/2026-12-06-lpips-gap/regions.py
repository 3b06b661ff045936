#!/usr/bin/env python3
"""The LPIPS-gap study's diagnosis: each row against `full` by image region and in the source view, paired over
pairs and seeds (the evaluator's scoring.regions records), with cluster-bootstrap 95% intervals over pairs.

Writes regions.md (tables), regions.csv and regions.svg (LPIPS difference by region) next to this script; with
rows named after EVAL_DIR (e.g. the candidate fixes), candidates.md, .csv and .svg for those rows instead.
Usage: python3 lab/2026-12-06-lpips-gap/regions.py [EVAL_DIR [ROW ...]]   (default out/experiments/lpips/eval)
"""
import csv
import glob
import json
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROWS = ["pixel_supports", "dense_decoder"]
OUT = "regions"  # the output files' name
REGIONS = ["all", "near", "far", "textured", "flat", "silhouette", "interior", "source_view"]
FIELDS = ["lpips", "psnr", "detail", "density"]
SEEDS = [0, 1]


def load(path):
    """Pair index -> record, failing with the file's name on a damaged line."""
    out = {}
    with open(path) as f:
        for k, line in enumerate(f, 1):
            try:
                r = json.loads(line)
            except json.JSONDecodeError as e:
                sys.exit(f"{path}:{k}: {e}")
            out[r["index"]] = r
    return out


def value(record, region, field):
    g = record.get("source_view") if region == "source_view" else record.get("regions", {}).get(region)
    v = None if g is None else g.get(field)
    return v if isinstance(v, (int, float)) else None


def interval(diffs, resamples=2000, seed=0):
    """Mean of per-pair differences (each pair's seeds averaged) and a percentile bootstrap interval over pairs."""
    per_pair = [sum(d) / len(d) for d in diffs.values() if d]
    if not per_pair:
        return None
    rng = random.Random(seed)
    n = len(per_pair)
    means = sorted(sum(rng.choice(per_pair) for _ in range(n)) / n for _ in range(resamples))
    return sum(per_pair) / n, means[int(0.025 * resamples)], means[int(0.975 * resamples) - 1], n


def results(eval_dir, dataset, row, seed):
    paths = [p for pattern in (f"results_{row}-s{seed}_*.jsonl", f"results_{row}-s{seed}.jsonl")
             for p in glob.glob(os.path.join(eval_dir, dataset, pattern))]
    if len(paths) != 1:
        sys.exit(f"{eval_dir}/{dataset}: expected one results file of {row} seed {seed}, found {paths}")
    return load(paths[0])


def main():
    global ROWS, OUT
    eval_dir = sys.argv[1] if len(sys.argv) > 1 else "out/experiments/lpips/eval"
    if len(sys.argv) > 2:
        ROWS, OUT = sys.argv[2:], "candidates"
    datasets = sorted(d for d in os.listdir(eval_dir) if os.path.isfile(os.path.join(eval_dir, d, "manifest.json")))
    if not datasets:
        sys.exit(f"{eval_dir}: no scored datasets")
    table, means = [], []
    for dataset in datasets:
        logs = {(row, s): results(eval_dir, dataset, row, s) for row in ["full"] + ROWS for s in SEEDS}
        for row in ["full"] + ROWS:  # each row's own means (detail and density are ratios, not differences)
            for region in REGIONS:
                vals = {f: [value(r, region, f) for s in SEEDS for r in logs[(row, s)].values()] for f in FIELDS}
                vals = {f: [v for v in vs if v is not None] for f, vs in vals.items()}
                means.append([dataset, row, region] + [sum(v) / len(v) if v else None for v in vals.values()])
        for row in ROWS:  # LPIPS by baseline bin, over the whole mask
            for b in sorted({r["bin"] for r in logs[("full", 0)].values()}):
                diffs = {}
                for s in SEEDS:
                    full, other = logs[("full", s)], logs[(row, s)]
                    for i in full.keys() & other.keys():
                        if full[i]["bin"] == b and None not in (full[i].get("lpips_squeeze"), other[i].get("lpips_squeeze")):
                            diffs.setdefault(i, []).append(other[i]["lpips_squeeze"] - full[i]["lpips_squeeze"])
                iv = interval(diffs)
                if iv:
                    table.append([dataset, row, f"bin {b}", "lpips", *iv])
        for row in ROWS:
            for region in REGIONS:
                for field in FIELDS:
                    diffs = {}
                    for s in SEEDS:
                        full, other = logs[("full", s)], logs[(row, s)]
                        for i in full.keys() & other.keys():
                            a, b = value(other[i], region, field), value(full[i], region, field)
                            if a is not None and b is not None:
                                diffs.setdefault(i, []).append(a - b)
                    iv = interval(diffs)
                    if iv:
                        table.append([dataset, row, region, field, *iv])
    with open(os.path.join(HERE, OUT + ".csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["dataset", "row", "region", "field", "diff", "lo", "hi", "pairs"])
        w.writerows([[*r[:4], *(f"{x:.5f}" for x in r[4:7]), r[7]] for r in table])
    write_markdown(table, means, datasets)
    write_svg(table, datasets)


def fmt(iv, digits):
    mean, lo, hi = iv
    tag = "" if lo > 0 or hi < 0 else " (no difference)"
    return f"{mean:+.{digits}f} [{lo:+.{digits}f}, {hi:+.{digits}f}]{tag}"


def write_markdown(table, means, datasets):
    lines = ["# Where the LPIPS gap lives: each row minus `full`, by region (generated by regions.py)", "",
             "Paired over pairs and both seeds; 95% cluster-bootstrap intervals over pairs (2000 resamples). LPIPS "
             "squeeze (lower is better), PSNR in dB. `source_view`: the scene rendered from the source camera "
             "against the photo.", ""]
    by = {(r[0], r[1], r[2], r[3]): r[4:7] for r in table}
    for dataset in datasets:
        lines += [f"## {dataset}", "", "| region | " + " | ".join(f"{row} LPIPS | {row} PSNR" for row in ROWS) + " |",
                  "|---|" + "---|" * (2 * len(ROWS))]
        for region in REGIONS:
            cells = []
            for row in ROWS:
                for field, digits in [("lpips", 4), ("psnr", 2)]:
                    iv = by.get((dataset, row, region, field))
                    cells.append(fmt(iv, digits) if iv else "n/a")
            lines.append(f"| {region} | " + " | ".join(cells) + " |")
        bins = sorted({r[2] for r in table if r[0] == dataset and r[2].startswith("bin ")})
        lines += ["", "LPIPS by baseline bin (whole mask; bins as in the evaluator, nearest first):", "",
                  "| bin | " + " | ".join(ROWS) + " |", "|---|" + "---|" * len(ROWS)]
        for b in bins:
            lines.append(f"| {b[4:]} | " + " | ".join(fmt(by[(dataset, row, b, "lpips")], 4)
                                                     if (dataset, row, b, "lpips") in by else "n/a" for row in ROWS) + " |")
        lines += ["", "Each row's means: LPIPS, detail (below 1 = blurrier than the target), Gaussian centres per "
                  "pixel.", "", "| region | " + " | ".join(f"{row} LPIPS | detail | density"
                                                           for row in ["full"] + ROWS) + " |",
                  "|---|" + "---|" * (3 * (len(ROWS) + 1))]
        own = {(m[1], m[2]): m[3:] for m in means if m[0] == dataset}
        for region in REGIONS:
            cells = []
            for row in ["full"] + ROWS:
                lp, _, detail, density = own[(row, region)]
                cells += [f"{x:.{d}f}" if x is not None else "n/a" for x, d in [(lp, 4), (detail, 3), (density, 2)]]
            lines.append(f"| {region} | " + " | ".join(cells) + " |")
        lines.append("")
    with open(os.path.join(HERE, OUT + ".md"), "w") as f:
        f.write("\n".join(lines))


def write_svg(table, datasets):
    """One panel per dataset: LPIPS difference (row - full) per region, a dot and its interval for each row."""
    by = {(r[0], r[1], r[2]): r[4:7] for r in table if r[3] == "lpips"}
    lo = min([v[1] for v in by.values()] + [0]) * 1.1
    hi = max([v[2] for v in by.values()] + [0]) * 1.1
    pw, ph, left, top = 300, 24 * len(REGIONS) + 50, 90, 30
    width, height = left + len(datasets) * (pw + 30), ph + top + 40
    palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"]
    colors = {row: palette[k % len(palette)] for k, row in enumerate(ROWS)}
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" '
           'font-size="11">', f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{left}" y="16" font-size="13">LPIPS, row minus full (left of 0: the row is better), '
           '95% intervals</text>']
    for k, dataset in enumerate(datasets):
        x0 = left + k * (pw + 30)
        sx = lambda v: x0 + (v - lo) / (hi - lo) * pw
        svg.append(f'<text x="{x0 + pw / 2}" y="{top + 10}" text-anchor="middle">{dataset}</text>')
        svg.append(f'<line x1="{sx(0)}" y1="{top + 18}" x2="{sx(0)}" y2="{top + ph - 20}" stroke="#888"/>')
        for j, region in enumerate(REGIONS):
            y = top + 30 + 24 * j
            if k == 0:
                svg.append(f'<text x="{left - 6}" y="{y + 4}" text-anchor="end">{region}</text>')
            for m, row in enumerate(ROWS):
                iv = by.get((dataset, row, region))
                if not iv:
                    continue
                yy = y - 4 + 8 * m / max(1, len(ROWS) - 1)
                svg.append(f'<line x1="{sx(iv[1]):.1f}" y1="{yy}" x2="{sx(iv[2]):.1f}" y2="{yy}" '
                           f'stroke="{colors[row]}" stroke-width="2"/>')
                svg.append(f'<circle cx="{sx(iv[0]):.1f}" cy="{yy}" r="3" fill="{colors[row]}"/>')
        for t, anchor in ((lo, "start"), (0, "middle"), (hi, "end")):
            svg.append(f'<text x="{sx(t):.1f}" y="{top + ph - 6}" text-anchor="{anchor}">{t:+.3f}</text>')
    for m, row in enumerate(ROWS):
        svg.append(f'<circle cx="{left + 10 + 160 * m}" cy="{height - 12}" r="4" fill="{colors[row]}"/>'
                   f'<text x="{left + 18 + 160 * m}" y="{height - 8}">{row}</text>')
    svg.append("</svg>")
    with open(os.path.join(HERE, OUT + ".svg"), "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Quality inside and beyond the training range, from an evaluator's output folder.

Splits each method's scored pairs by the frame gap between source and target (training tuples take targets within
+-10 frames of the context) and by baseline bin, and gives mean PSNR / SSIM / LPIPS-squeeze / hole rate with a
bootstrap 95% interval over pairs for PSNR. Usage: frame_gap.py OUT_DIR [--gap 10]
"""
import argparse
import glob
import json
import os
import random


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def interval(xs, resamples=2000, seed=0):
    if len(xs) < 2:
        return float("nan"), float("nan")
    rng = random.Random(seed)
    means = sorted(mean([rng.choice(xs) for _ in xs]) for _ in range(resamples))
    return means[int(0.025 * resamples)], means[int(0.975 * resamples) - 1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--gap", type=int, default=10, help="largest frame gap of a training tuple")
    a = ap.parse_args()
    print("| dataset | method | group | pairs | baseline m | PSNR [95%] | SSIM | LPIPS | holes % |")
    print("|---|---|---|---|---|---|---|---|---|")
    for manifest_path in sorted(glob.glob(os.path.join(a.out, "*", "manifest.json"))):
        folder = os.path.dirname(manifest_path)
        manifest = json.load(open(manifest_path))
        pairs = manifest["pairs"]
        bins = [b["bin"] for b in manifest["bins"]]
        for results in sorted(glob.glob(os.path.join(folder, "results_*.jsonl"))):
            method = os.path.basename(results)[len("results_"):-len(".jsonl")]
            rows = [json.loads(line) for line in open(results) if line.strip()]
            groups = {}
            for r in rows:
                p = pairs[r["index"]]
                gap = abs(p["target_index"] - p["source_index"])
                side = f"gap <= {a.gap}" if gap <= a.gap else f"gap > {a.gap}"
                for key in ("all " + side, bins[p["bin"]] + " " + side, bins[p["bin"]]):
                    groups.setdefault(key, []).append(r)
            order = sorted(groups, key=lambda k: (not k.startswith("all"), k))
            for key in order:
                g = groups[key]
                psnr = [r["psnr"] for r in g if r.get("psnr") is not None]
                lo, hi = interval(psnr)
                holes = [r["hole_rate"] for r in g if r.get("hole_rate") is not None]
                print(f"| {manifest['dataset']} | {method} | {key} | {len(g)} | {mean([r['baseline'] for r in g]):.2f} | "
                      f"{mean(psnr):.2f} [{lo:.2f}, {hi:.2f}] | {mean([r['ssim'] for r in g]):.3f} | "
                      f"{mean([r.get('lpips_squeeze', float('nan')) for r in g]):.3f} | {100 * mean(holes):.2f} |")


if __name__ == "__main__":
    main()

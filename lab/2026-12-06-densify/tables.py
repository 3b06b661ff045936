#!/usr/bin/env python3
"""Tables of the densification study from the evaluator's per-pair logs: PSNR per bin with 95% bootstrap intervals,
the densification scores, and paired differences (to dataset depth, to prompt-only) with intervals.
Usage: tables.py OUT_DIR [OUT_DIR ...] > tables.md   (OUT_DIR: an infinisplat-eval scoring.out folder)"""
import json
import os
import random
import sys

BINS = ["[0,0.5)", "[0.5,1)", "[1,2)", "[2,inf)"]


def load(out):
    data = {}
    for dataset in sorted(os.listdir(out)):
        folder = os.path.join(out, dataset)
        if not os.path.isdir(folder):
            continue
        for f in sorted(os.listdir(folder)):
            if f.startswith("results_") and f.endswith(".jsonl"):
                rows = [json.loads(line) for line in open(os.path.join(folder, f)) if line.strip()]
                if rows:
                    data.setdefault(dataset, {})[rows[0]["method"]] = {r["index"]: r for r in rows}
    return data


def interval(values, reps=2000, seed=0):
    if not values:
        return float("nan"), float("nan"), float("nan")
    rng = random.Random(seed)
    n = len(values)
    means = sorted(sum(rng.choice(values) for _ in range(n)) / n for _ in range(reps))
    return sum(values) / n, means[int(0.025 * reps)], means[int(0.975 * reps) - 1]


def fmt(m, lo, hi, signed=False):
    if m != m:
        return "n/a"
    s = "{:+.2f}" if signed else "{:.2f}"
    return (s + " [" + s + ", " + s + "]").format(m, lo, hi)


def densify(rows, key):
    vals = [r[key] for r in rows if key in r and r[key].get("pixels", 0) > 0]
    if not vals:
        return "n/a", "n/a"
    return "%.3f" % (sum(v["abs_rel"] for v in vals) / len(vals)), "%.3f" % (sum(v["delta1"] for v in vals) / len(vals))


def partner(method, kind):
    """The method a row is compared with: dataset depth, or prompt-only, under the same perturbation and far rule."""
    suffix = "-kinect" if method.endswith("-kinect") else ""
    core = method[: -len(suffix)] if suffix else method
    if kind == "dataset":
        return "dataset" + suffix
    far = core[core.index("-far"):] if "-far" in core else ""
    return "prompts" + far + suffix


def main():
    for out in sys.argv[1:]:
        for dataset, methods in load(out).items():
            print(f"### {dataset} ({out})\n")
            print("| method | pairs | PSNR all | " + " | ".join("PSNR " + b for b in BINS) +
                  " | − dataset (dB) | − prompts (dB) | AbsRel unprompted | δ<1.25 unprompted | AbsRel removed | δ<1.25 removed |")
            print("|---" * (10 + len(BINS)) + "|")
            for name in sorted(methods, key=lambda n: (n.endswith("-kinect"), n)):
                # A pair with nothing to score (mask_depth = seen, the sensor returned nothing there) has no PSNR.
                rows = [r for r in methods[name].values() if r["psnr"] is not None]
                unscored = len(methods[name]) - len(rows)
                cells = [name, str(len(rows)) + (" (+%d empty)" % unscored if unscored else ""),
                         fmt(*interval([r["psnr"] for r in rows]))]
                for b in range(len(BINS)):
                    cells.append(fmt(*interval([r["psnr"] for r in rows if r["bin"] == b])))
                for kind in ("dataset", "prompts"):
                    other = methods.get(partner(name, kind))
                    if other is None and kind == "prompts":  # the development scenes name it by its far rule
                        suffix = "-kinect" if name.endswith("-kinect") else ""
                        other = methods.get("prompts-farkeep" + suffix)
                    if other is None or other is methods[name]:
                        cells.append("")
                        continue
                    diffs = [r["psnr"] - other[i]["psnr"] for i, r in methods[name].items()
                             if i in other and r["psnr"] is not None and other[i]["psnr"] is not None]
                    cells.append(fmt(*interval(diffs), signed=True))
                cells += [*densify(rows, "densify_unprompted"), *densify(rows, "densify_removed")]
                print("| " + " | ".join(cells) + " |")
            print()


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Summarizes run.sh's rounds.txt: for each benchmark setting and tree, the range over the rounds (markdown)."""
import re
import sys
from collections import OrderedDict

HEADER = re.compile(r"^== \S+ (?:round \d+|paper) (base|head)(?: (\w+))?: (\S+)\s*(.*)$")
PREDICT = re.compile(r"^(.+?)\s+\d+x\d+\s+supports\s+(\d+) \|.*encoder\s+([\d.]+) decoder\s+([\d.]+).*total\s+([\d.]+) ms"
                     r" \| peak\s+(\d+) MB")
TRAIN = re.compile(r"^\s+total\s+([\d.]+)$")
RENDER = re.compile(r"^\|\s*(\w+)\s*\|")


def rows(path):
    """(benchmark, setting, tree, figure name, value) for every figure in the file."""
    tree = precision = bench = args = None
    for line in open(path, encoding="utf-8"):
        line = line.rstrip("\n")
        m = HEADER.match(line)
        if m:
            tree, precision, bench, args = m.group(1), m.group(2) or "fp32", m.group(3), m.group(4)
            if tree == "head":
                p = re.search(r"--precision (\w+)", args)
                precision = p.group(1) if p else precision
            continue
        if bench == "bench_predict" and (m := PREDICT.match(line)):
            setting = m.group(1).strip()
            if "--paper" in args and not setting.startswith(("paper:", "the default at the paper's size")):
                continue  # a --paper run repeats the small settings once more: the rounds have them
            yield bench, setting, f"{tree} {precision}", "encoder / decoder / total ms", \
                (float(m.group(3)), float(m.group(4)), float(m.group(5)))
        elif bench == "bench_train_step" and (m := TRAIN.match(line)):
            config = args.split()[-1] if "--precision" not in args else args.split()[-3]
            yield bench, config, f"{tree} {precision}", "step ms", (float(m.group(1)),)
        elif bench == "bench_render" and (m := RENDER.match(line)) and m.group(1) != "case":
            cells = [c.strip() for c in line.strip("|").split("|")]
            # columns: case N image visible isects first fwd f+b ... first f+b (last)
            yield bench, m.group(1), tree, "fwd / f+b / first f+b ms", \
                (float(cells[6]), float(cells[7]), float(cells[-1]))


def span(values):
    lo, hi = min(values), max(values)
    return f"{lo:.0f}" if lo == hi and lo >= 10 else (f"{lo:.1f}" if lo == hi else
                                                       (f"{lo:.0f}–{hi:.0f}" if lo >= 100 else f"{lo:.1f}–{hi:.1f}"))


def main(path):
    table = OrderedDict()
    for bench, setting, tree, what, values in rows(path):
        table.setdefault((bench, setting, what), OrderedDict()).setdefault(tree, []).append(values)
    print("| benchmark | setting | figure | tree | rounds | range over the rounds |")
    print("|---|---|---|---|---|---|")
    for (bench, setting, what), trees in table.items():
        for tree, runs in trees.items():
            ranges = " / ".join(span([r[k] for r in runs]) for k in range(len(runs[0])))
            print(f"| {bench} | {setting} | {what} | {tree} | {len(runs)} | {ranges} |")


if __name__ == "__main__":
    main(sys.argv[1])

#!/bin/bash
# The first version's evaluation run, stopped after the rooms set (out/experiments/fill_far, commit 7535295's
# lab/2026-11-27-fill-far/configs/eval_fill_far.json): far fill against blend, paired, bins all and [2,inf).
set -e
P=lab/2026-11-26-surface-frame/paired.py
R=out/experiments/fill_far
for e in 1 2 4 8; do
  echo "== far-side $e px, both seeds"
  python3 $P $R "far_depth_edge_holes$e+far_s1_depth_edge_holes$e" "blend_depth_edge_holes$e+blend_s1_depth_edge_holes$e" all,3
done
for e in 2 8; do
  echo "== two-sided $e px, seed 0"
  python3 $P $R "far_both_depth_edge_holes$e" "blend_both_depth_edge_holes$e" all,3
done

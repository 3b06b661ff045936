#!/bin/bash
# Paired differences on the development scenes (full_s0, dataset depth, fill_px = 32), far fill against blend, for the
# first version's run (out/experiments/fill_far_dev, commit 7535295), the second's (out/experiments/fill_far_dev2,
# f1e45f9) and the second's after the review's fix of its width test (out/experiments/fill_far_dev3, 8f72458).
set -e
P=lab/2026-11-26-surface-frame/paired.py
for R in out/experiments/fill_far_dev out/experiments/fill_far_dev2 out/experiments/fill_far_dev3; do
  echo "#### $R"
  for e in 0 1 2 4 8; do
    echo "== far-side $e px"
    python3 $P $R "far_depth_edge_holes$e" "blend_depth_edge_holes$e" all
  done
  for e in 2 8; do
    echo "== two-sided $e px"
    python3 $P $R "far_both_depth_edge_holes$e" "blend_both_depth_edge_holes$e" all
  done
  for h in 0_1 0_3; do
    echo "== random holes $h"
    python3 $P $R "far_holes_depth_holes$h" "blend_holes_depth_holes$h" all
  done
done

#!/bin/bash
# Paired differences on the evaluation sets (both seeds of full averaged per pair), from the repository root after
# lab/2026-11-27-edge-shadow/configs/eval_edge_holes.json has scored: the fill against no fill at each drop-out width, and the fill
# at each width against the fill without drop-outs. Bins: all and [2,inf).
root=${1:-out/experiments/edge_holes}
P=lab/2026-11-26-surface-frame/paired.py
for e in 0 1 2 4 8; do
  echo "== fill against no fill, edge drop-outs $e px"
  python3 $P "$root" "full_fill32_depth_edge_holes$e+full_fill32_s1_depth_edge_holes$e" \
    "full_depth_edge_holes$e+full_s1_depth_edge_holes$e" all,3
done
for e in 1 2 4 8; do
  echo "== fill at $e px against the fill without drop-outs"
  python3 $P "$root" "full_fill32_depth_edge_holes$e+full_fill32_s1_depth_edge_holes$e" \
    "full_fill32_depth_edge_holes0+full_fill32_s1_depth_edge_holes0" all,3
done

#!/bin/bash
# Issue 17's comparison under edge drop-outs, all with fill_px = 32: full against the pixel-supports and
# dense-decoder rows (both seeds averaged per pair), at 0, 2 and 8 px. From the repository root after
# lab/2026-11-27-edge-shadow/configs/eval_edge_holes.json has scored. Bins: all and [2,inf).
root=${1:-out/experiments/edge_holes}
P=lab/2026-11-26-surface-frame/paired.py
for row in pixel_supports dense_decoder; do
  for e in 0 2 8; do
    echo "== full against $row, both with the fill, edge drop-outs $e px"
    python3 $P "$root" "full_fill32_depth_edge_holes$e+full_fill32_s1_depth_edge_holes$e" \
      "${row}_fill32_depth_edge_holes$e+${row}_fill32_s1_depth_edge_holes$e" all,3
  done
done

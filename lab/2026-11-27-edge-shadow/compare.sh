#!/bin/bash
# Paired differences of the far-side report, from the repository root once lab/2026-11-27-fill-far/configs/eval_edge_shadow.json
# and lab/2026-11-27-edge-shadow/configs/eval_edge_holes.json have scored. Links both runs' results into one folder (the same
# pairs and masks), then compares; both seeds of full are averaged per pair. Bins: all and [2,inf).
set -e
far=${1:-out/experiments/edge_shadow}
both=${2:-out/experiments/edge_holes}
root=${3:-out/experiments/edge_shadow_both}
P=lab/2026-11-26-surface-frame/paired.py
for d in "$far"/*/; do
  s=$(basename "$d")
  [ -d "$both/$s" ] || continue
  mkdir -p "$root/$s"
  ln -sf "$(realpath "$d")"/results_*.jsonl "$(realpath "$both/$s")"/results_*.jsonl "$root/$s/"
done
nofill0="full_depth_edge_holes0+full_s1_depth_edge_holes0"
fill0="full_fill32_depth_edge_holes0+full_fill32_s1_depth_edge_holes0"
for e in 1 2 4 8; do
  far_nofill="far_depth_edge_holes$e+far_s1_depth_edge_holes$e"
  far_fill="far_fill32_depth_edge_holes$e+far_fill32_s1_depth_edge_holes$e"
  echo "== $e px: far side, fill against no fill"
  python3 $P "$root" "$far_fill" "$far_nofill" all,3
  echo "== $e px: far side without the fill, against no drop-outs"
  python3 $P "$root" "$far_nofill" "$nofill0" all,3
  echo "== $e px: far side with the fill, against the fill without drop-outs"
  python3 $P "$root" "$far_fill" "$fill0" all,3
  echo "== $e px: far side against both sides, without the fill"
  python3 $P "$root" "$far_nofill" "full_depth_edge_holes$e+full_s1_depth_edge_holes$e" all,3
  echo "== $e px: far side against both sides, with the fill"
  python3 $P "$root" "$far_fill" "full_fill32_depth_edge_holes$e+full_fill32_s1_depth_edge_holes$e" all,3
done

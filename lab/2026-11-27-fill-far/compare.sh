#!/bin/bash
# Paired differences of the far fill's report, from the repository root once lab/2026-11-27-fill-far/configs/eval_fill_far.json
# has scored. Links its results beside the blend's from the earlier runs on the same pairs and masks (identical
# manifests): edge_shadow (far-side bands), edge_holes (no drop-outs, two-sided bands), fill (random holes). Both
# seeds of full are averaged per pair. Bins: all and [2,inf).
set -e
new=${1:-out/experiments/fill_far2}
root=${2:-out/experiments/fill_far_both}
P=lab/2026-11-26-surface-frame/paired.py
for d in "$new"/*/; do
  s=$(basename "$d")
  mkdir -p "$root/$s"
  for src in "$new" out/experiments/edge_shadow out/experiments/edge_holes out/experiments/fill; do
    ln -sf "$(realpath "$src/$s")"/results_*.jsonl "$root/$s/"
  done
done
seeds() { echo "$1_$2+$1_s1_$2"; }  # method m, suffix x -> m_x + m_s1_x
for e in 1 2 4 8; do
  echo "== far-side $e px: far fill against blend"
  python3 $P "$root" "$(seeds fill_far depth_edge_holes$e)" "$(seeds far_fill32 depth_edge_holes$e)" all,3
  echo "== far-side $e px: far fill against the blend without drop-outs"
  python3 $P "$root" "$(seeds fill_far depth_edge_holes$e)" "$(seeds full_fill32 depth_edge_holes0)" all,3
done
echo "== no drop-outs: far fill against blend"
python3 $P "$root" "$(seeds fill_far depth_edge_holes0)" "$(seeds full_fill32 depth_edge_holes0)" all,3
for e in 2 8; do
  echo "== two-sided $e px: far fill against blend"
  python3 $P "$root" "$(seeds fill_far_both depth_edge_holes$e)" "$(seeds full_fill32 depth_edge_holes$e)" all,3
done
echo "== random holes 30%: far fill against blend"
python3 $P "$root" "$(seeds fill_far_holes depth_holes0_3)" "$(seeds full_fill32 depth_holes0_3)" all,3

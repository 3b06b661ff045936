#!/bin/bash
# The review's fix of the width test (8f72458) against the scored second version (f1e45f9) on rooms, the one
# evaluation set whose rescoring finished (out/experiments/fill_far3): both seeds averaged, paired, all and [2,inf).
set -e
P=lab/2026-11-26-surface-frame/paired.py
root=${1:-out/experiments/fill_far_fix_rooms}
mkdir -p "$root/rooms-heldout"
cp -f out/experiments/fill_far2/rooms-heldout/results_fill_far*.jsonl "$root/rooms-heldout/"
for f in out/experiments/fill_far3/rooms-heldout/results_fill_far*.jsonl; do
  b=$(basename "$f")
  cp -f "$f" "$root/rooms-heldout/${b/results_fill_far/results_fixed}"
done
both() { echo "$1_$2+$1_s1_$2"; }
for x in depth_edge_holes0 depth_edge_holes1 depth_edge_holes2 depth_edge_holes4 depth_edge_holes8; do
  echo "== far-side ${x#depth_edge_holes} px: fixed against scored"
  python3 $P "$root" "$(both fixed $x)" "$(both fill_far $x)" all,3
done
for x in depth_edge_holes2 depth_edge_holes8; do
  echo "== two-sided ${x#depth_edge_holes} px: fixed against scored"
  python3 $P "$root" "$(both fixed_both $x)" "$(both fill_far_both $x)" all,3
done
echo "== random holes 30%: fixed against scored"
python3 $P "$root" "$(both fixed_holes depth_holes0_3)" "$(both fill_far_holes depth_holes0_3)" all,3

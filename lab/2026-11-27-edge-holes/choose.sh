#!/bin/bash
# Run from the repository root after eval_fill_snap_dev.json (commit 31864eb; deleted with fill_snap in ec7499f) has scored.
# Paired differences of each fill_snap candidate against the blend on the development scenes (the rule's measures).
root=${1:-out/experiments/snap_dev}
P=lab/2026-11-26-surface-frame/paired.py
edge() { echo "$1_depth_edge_holes1+$1_depth_edge_holes2+$1_depth_edge_holes4+$1_depth_edge_holes8"; }
B=full_fill32
for c in full_fill32_snap5 full_fill32_snap10 full_fill32_snap20; do
  echo "== $c against the blend"
  echo -n "no holes:   "; python3 $P "$root" ${c}_depth_edge_holes0 ${B}_depth_edge_holes0 all
  echo -n "holes 10%:  "; python3 $P "$root" ${c}_depth_holes0_1 ${B}_depth_holes0_1 all
  echo -n "holes 30%:  "; python3 $P "$root" ${c}_depth_holes0_3 ${B}_depth_holes0_3 all
  echo -n "edge mean:  "; python3 $P "$root" "$(edge $c)" "$(edge $B)" all
  for e in 1 2 4 8; do echo -n "edge $e px:  "; python3 $P "$root" ${c}_depth_edge_holes$e ${B}_depth_edge_holes$e all; done
done

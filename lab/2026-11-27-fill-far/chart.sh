#!/bin/bash
# One chart of blend against the far fill on far-side bands: copies the scored results and their stamps of
# eval_edge_shadow.json's far+fill32 methods and eval_fill_far.json's fill_far methods into one folder (the evaluator
# refuses to append through links), then runs eval_fill_far_chart.json, which resumes every pair (nothing is scored
# again) and writes stability.png there.
set -e
root=out/experiments/fill_far_chart
for s in rooms-heldout courtyard-colmap atrium-nerfstudio; do
  mkdir -p "$root/$s"
  cp -f "out/experiments/edge_shadow/$s"/results_far_fill32*.jsonl* "$root/$s/"
  cp -f "out/experiments/fill_far2/$s"/results_fill_far_depth*.jsonl* \
    "out/experiments/fill_far2/$s"/results_fill_far_s1_depth*.jsonl* "$root/$s/"
done
build/infinisplat-eval --config lab/2026-11-27-fill-far/configs/eval_fill_far_chart.json

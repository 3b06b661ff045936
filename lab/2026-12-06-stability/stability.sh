#!/usr/bin/env bash
# The stability suite in one resumable command, on the ablation recipe's rows (configs/recipe/ablation.json,
# seed 0 of full, pixel_supports and dense_decoder): every perturbation sweep for the three rows and lift, the LiDAR
# prompt sweeps for the full model (eval_stability.json); the rows unperturbed with paired differences and a failure
# gallery, and the prior-shape axis: the LiDAR variant's fit, prompt-only and blend densifications on the learned,
# a random and a warped prior, clean and with the kinect sensor preset, beside dataset depth (eval_failures.json;
# lab/2026-12-06-densify); the held-out rooms at three resolutions (eval_resolution.json). Scored pairs are kept,
# so re-running only writes the reports again.
# Usage, from the repository root or anywhere: lab/2026-12-06-stability/stability.sh [infinisplat-eval options, e.g. --set scoring.max_per_bin=2]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"
bin="${BUILD_DIR:-$root/build}"
for file in out/experiments/ablation/runs/{full,pixel_supports,dense_decoder}_s0/checkpoints/last.safetensors \
  out/experiments/depth/depth_net.safetensors; do
  [ -f "$file" ] || { echo "stability.sh: $file is missing; train those rows and the depth prior first (scripts/experiments.sh --rows full,pixel_supports,dense_decoder --seeds 0 --stage train)" >&2; exit 1; }
done
scripts/build.sh
for config in eval_stability eval_failures eval_resolution; do
  echo "== lab/2026-12-06-stability/configs/$config.json"
  "$bin/infinisplat-eval" --config "lab/2026-12-06-stability/configs/$config.json" "$@"
done
echo "reports: out/experiments/stability, out/experiments/failures, out/experiments/stability_resolution"

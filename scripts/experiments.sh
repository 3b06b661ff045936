#!/usr/bin/env bash
# The ablation table (issue "Evidence") in one resumable command: set up and build, generate the experiment
# data, train the learned depth priors (rooms-only, and the mixed-style ones of the RGB variants), then
# train, score and report every row of
# configs/recipe/ablation.json. Re-running skips what is finished; Ctrl-C is safe at any point.
# Usage: scripts/experiments.sh [infinisplat-experiment options, e.g. --rows full,pixel_supports --seeds 0]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bin="${BUILD_DIR:-$root/build}"
config="${EXPERIMENT_CONFIG:-configs/recipe/ablation.json}"
start=$(date +%s)
stamp() { echo; echo "== $1  ($(( $(date +%s) - start )) s elapsed)"; }

stamp "1. set-up and build"
scripts/setup.sh
scripts/build.sh

stamp "2. experiment data (configs/recipe/data.json)"
if [ ! -f out/experiments/data/hypersim/metadata_images_split_scene_v1.csv ]; then
  "$bin/infinisplat" generate --config configs/recipe/data.json
else
  echo "reusing out/experiments/data"
fi

stamp "3. the learned depth prior for the RGB variant (configs/recipe/depth.json)"
"$bin/infinisplat-train" --config configs/recipe/depth.json --resume auto

stamp "3b. the recommended RGB prior of the rgb_wide_aug_clutter_flip_height variant (scripts/train_depth_prior.sh)"
scripts/train_depth_prior.sh wide_aug_clutter

stamp "4. rows: train, score, report ($config)"
"$bin/infinisplat-experiment" --config "$config" "$@"

stamp "done"
echo "report: $(sed -n 's/.*"out": "\([^"]*\)".*/\1/p' "$config" | head -1)/report.md"

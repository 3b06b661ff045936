#!/usr/bin/env bash
# The study's runs, resumable (re-run it to continue): the experiment data, seed 0 of both rows, then seed 1, then
# the scores (dev rooms, held-out rooms, courtyards, atria; also at 2x and 4x) and the report.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin="${BUILD_DIR:-build}"
cfg=lab/2026-12-06-display-holes/configs/ablation.json
[ -f out/experiments/data/hypersim/metadata_images_split_scene_v1.csv ] ||
  "$bin/infinisplat" generate --config configs/recipe/data.json
for seed in 0 1; do "$bin/infinisplat-experiment" --config "$cfg" --stage train --seeds "$seed"; done
"$bin/infinisplat-experiment" --config "$cfg" --stage eval
"$bin/infinisplat-experiment" --config "$cfg" --stage report

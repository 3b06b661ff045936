#!/usr/bin/env bash
# The LPIPS-gap study's runs, resumable (re-run it to continue): the two pixel-aligned rows of the paper's Table 2 on
# today's recipe, seed 0 of each first; the full rows are the display study's floor035 runs (today's recipe, linked,
# not retrained); then the scores and the report.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin="${BUILD_DIR:-build}"
cfg=lab/2026-12-06-lpips-gap/configs/ablation.json
mkdir -p out/experiments/lpips/runs
for seed in 0 1; do
  [ -e "out/experiments/lpips/runs/full_s$seed" ] ||
    ln -s "../../display/runs/floor035_s$seed" "out/experiments/lpips/runs/full_s$seed"
done
for seed in 0 1; do "$bin/infinisplat-experiment" --config "$cfg" --stage train --seeds "$seed"; done
"$bin/infinisplat-experiment" --config "$cfg" --stage eval
"$bin/infinisplat-experiment" --config "$cfg" --stage report

#!/usr/bin/env bash
# bf16 training against fp32, resumable (re-run it to continue): the fp32 rows are the display study's runs of the
# same recipe (linked, not retrained); the bf16 rows train here; then both are scored on the same pairs, in fp32.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin="${BUILD_DIR:-build}"
cfg=lab/2026-12-06-bf16/configs/train.json
mkdir -p out/experiments/bf16train/runs
for seed in 0 1; do
  [ -e "out/experiments/bf16train/runs/full_s$seed" ] ||
    ln -s "../../display/runs/full_s$seed" "out/experiments/bf16train/runs/full_s$seed"
done
for seed in 0 1; do "$bin/infinisplat-experiment" --config "$cfg" --stage train --seeds "$seed"; done
"$bin/infinisplat-experiment" --config "$cfg" --stage eval
"$bin/infinisplat-experiment" --config "$cfg" --stage report

#!/usr/bin/env bash
# The stability suite in one resumable command, on the pure-area-sampling table's trained checkpoints
# (configs/experiments/ablation_levers.json): the rows unperturbed per bin and motion type with a failure gallery
# (eval_diagnosis.json), the perturbation sweeps (eval_stability.json) and the held-out rooms at three
# resolutions (eval_resolution.json). Scored pairs are kept, so re-running only writes the reports again.
# Usage: scripts/stability.sh [infinisplat-eval options, e.g. --set scoring.max_per_bin=2]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bin="${BUILD_DIR:-$root/build}"
for run in full_s0 pixel_supports_s0 dense_decoder_s0; do
  ck="out/experiments/levers/runs/$run/checkpoints/last.safetensors"
  [ -f "$ck" ] || { echo "stability.sh: $ck is missing; train those rows first (EXPERIMENT_CONFIG=configs/experiments/ablation_levers.json scripts/experiments.sh --rows full,pixel_supports,dense_decoder --stage train)" >&2; exit 1; }
done
scripts/build.sh
for config in eval_diagnosis eval_stability eval_resolution; do
  echo "== configs/experiments/$config.json"
  "$bin/infinisplat-eval" --config "configs/experiments/$config.json" "$@"
done
echo "reports: out/experiments/diagnosis, out/experiments/stability, out/experiments/stability_resolution"

#!/usr/bin/env bash
# The densification study, resumable (the evaluator keeps every scored pair): the development scenes first
# (configs/dev.json: the far rule and the default chosen there; dev_color_range.json: the colour range), then the
# evaluation sets (configs/study.json, and study_seen.json: the kinect rows masked by the sensor's depth), then the
# tables. Needs the display study's full_s0 checkpoint and a learned depth net (README, "Inputs").
# The second sitting (stage street): the street-trained prior (README, "A prior trained on another style") on the
# development scenes and the evaluation sets, the decisive rows at 4 pairs per bin, the priors' shape error.
# Usage, from anywhere: lab/2026-12-06-densify/run.sh [dev|study|street|tables|all] [infinisplat-eval options]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"
here=lab/2026-12-06-densify
bin="${BUILD_DIR:-$root/build}"
stage="${1:-all}"
[ $# -gt 0 ] && shift
for file in out/experiments/display/runs/full_s0/checkpoints/last.safetensors out/densify/depth_net.safetensors; do
  [ -f "$file" ] || { echo "run.sh: $file is missing (README, Inputs)" >&2; exit 1; }
done
if [ "$stage" = dev ] || [ "$stage" = all ]; then
  nice -n 19 "$bin/infinisplat-eval" --config "$here/configs/dev.json" "$@"
  nice -n 19 "$bin/infinisplat-eval" --config "$here/configs/dev_color_range.json" "$@"
fi
if [ "$stage" = study ] || [ "$stage" = all ]; then
  nice -n 19 "$bin/infinisplat-eval" --config "$here/configs/study.json" "$@"
  nice -n 19 "$bin/infinisplat-eval" --config "$here/configs/study_seen.json" "$@"
fi
if [ "$stage" = street ] || [ "$stage" = all ]; then
  [ -f out/densify/depth_street/depth_net.safetensors ] || { echo "run.sh: the street-trained depth net is missing (README)" >&2; exit 1; }
  for config in dev_street study_street study_seen_street study16 study16_seen; do
    nice -n 19 "$bin/infinisplat-eval" --config "$here/configs/$config.json" "$@"
  done
  nice -n 19 "$bin/infinisplat" eval-depth --config "$here/configs/prior_shape.json" "$@"
fi
if [ "$stage" = tables ] || [ "$stage" = all ] || [ "$stage" = dev ] || [ "$stage" = study ] || [ "$stage" = street ]; then
  python3 "$here/tables.py" out/densify/dev out/densify/tune > "$here/tables_dev.md"
  [ -d out/densify/study ] && python3 "$here/tables.py" out/densify/study out/densify/study_seen > "$here/tables.md"
  [ -d out/densify/study16 ] && python3 "$here/tables.py" out/densify/study16 out/densify/study16_seen > "$here/tables16.md"
fi
echo "run.sh: tables in $here/tables_dev.md, $here/tables.md and $here/tables16.md"

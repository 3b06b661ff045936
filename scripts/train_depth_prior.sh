#!/usr/bin/env bash
# The generalizing RGB depth prior (issue "An RGB depth prior that generalizes"), resumable: set up and
# build, generate mixed-style depth data (rooms, desks, streets; 40-95 degree fields of view), train the
# prior from scratch (U-Net) and on the frozen pretrained SqueezeNet features, each focal-normalized with a
# scale-invariant + metric loss, then score both against the old rooms-only prior on the held-out rooms and
# the two other-style sets (AbsRel, delta < 1.25 per depth range). About an hour per prior on 2 cores.
# Usage: scripts/train_depth_prior.sh [unet|squeeze|eval ...]   (default: all three stages)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bin="${BUILD_DIR:-$root/build}"
stages=("$@")
[ ${#stages[@]} -gt 0 ] || stages=(unet squeeze eval)
scripts/setup.sh
scripts/build.sh
if [ ! -f out/depth_prior/data/hypersim/metadata_images_split_scene_v1.csv ]; then
  "$bin/infinisplat" generate --config configs/depth_prior/data.json
fi
for stage in "${stages[@]}"; do
  case "$stage" in
    unet|squeeze) "$bin/infinisplat-train" --config "configs/depth_prior/$stage.json" --resume auto ;;
    eval)
      [ -f out/experiments/data/hypersim/metadata_images_split_scene_v1.csv ] ||
        "$bin/infinisplat" generate --config configs/experiments/data.json
      "$bin/infinisplat" eval-depth --config configs/depth_prior/depth_eval.json ;;
    *) echo "train_depth_prior.sh: unknown stage '$stage' (unet | squeeze | eval)" >&2; exit 2 ;;
  esac
done
echo "report: out/depth_prior/eval/report.md"

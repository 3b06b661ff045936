#!/usr/bin/env bash
# The generalizing RGB depth prior (issue "An RGB depth prior that generalizes"), resumable: set up and
# build, generate mixed-style depth data (rooms, desks, streets; 40-95 degree fields of view), train the
# prior from scratch (U-Net) and on the frozen pretrained SqueezeNet features, each focal-normalized with a
# scale-invariant + metric loss; then the SqueezeNet prior on data with a fourth style (halls: large
# interiors), and again with a sky term (pixels without depth pushed far, then cut as sky); then the wide
# prior: 120 scenes of the four styles, 3000 steps (about 40 minutes on 2 cores); then score them against
# the old rooms-only prior on the held-out rooms and the two other-style sets (AbsRel, delta < 1.25 per depth
# range, scale and shape apart), with and without the camera-height scale, and on the wide data's
# validation scenes. Choices between priors go through the held-out-style check (loso_* stages), never the
# evaluation sets.
# 15-25 minutes per prior on 2 cores, except the wide one. Optional stages, not in the default list: the wide
# prior with training-time augmentation (wide_aug) and with a decoder twice as wide (wide_w64); the held-out-style
# check (loso_hall, loso_hall_aug: trained without the hall scenes, then scored on them with the loso_eval stage);
# the mirrored-photo average scored by that check (loso_eval_flip); 40 domain-randomized "clutter" scenes added to
# the augmented prior's data (wide_aug_clutter; loso_hall_aug_clutter, scored by loso_eval_clutter); the same
# check trained twice as long, 3000 steps (loso_hall_aug_clutter_long, scored by loso_eval_long); priors trained
# without the streets (loso_street_aug, loso_street_aug_clutter) and the check of decoders trained on held-out
# priors' depth (loso_trained_eval). Stages of rejected options left with their options: clutter scenes with large
# objects just ahead of the cameras (lab/2026-11-26-clutter-near), the fine-tuned encoder and the tuples' width
# (lab/2026-11-26-prior-tuned); each study names the commit that still runs them.
# Usage: scripts/train_depth_prior.sh [STAGE ...]   (the stages are listed in `known` below;
#        default: unet squeeze squeeze_hall squeeze_sky wide eval)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bin="${BUILD_DIR:-$root/build}"
known=(unet squeeze squeeze_hall squeeze_sky wide wide_aug wide_w64 loso_hall loso_hall_aug loso_eval loso_eval_flip
       wide_aug_clutter loso_hall_aug_clutter loso_eval_clutter loso_hall_aug_clutter_long loso_eval_long
       loso_street_aug loso_street_aug_clutter loso_trained_eval eval)
stages=("$@")
[ ${#stages[@]} -gt 0 ] || stages=(unet squeeze squeeze_hall squeeze_sky wide eval)
for stage in "${stages[@]}"; do  # a typo fails before the set-up and the build
  case " ${known[*]} " in
    *" $stage "*) ;;
    *) echo "train_depth_prior.sh: unknown stage '$stage' (one of: ${known[*]})" >&2
       exit 2 ;;
  esac
done
# The depth-prior configs live with the study that ran them last (lab/<date-topic>/configs/NAME.json); the recipe's
# own (data, depth, ablation) are in configs/recipe.
cfg() {  # $1: config name without .json -> its one path under lab/*/configs
  local found=(lab/*/configs/"$1".json)
  local hits=()
  for f in "${found[@]}"; do [ -f "$f" ] && hits+=("$f"); done
  [ ${#hits[@]} -eq 1 ] || { echo "train_depth_prior.sh: config $1.json found ${#hits[@]} times under lab/*/configs (want 1)" >&2; exit 2; }
  echo "${hits[0]}"
}
for stage in "${stages[@]}"; do  # a missing config fails before the set-up and the build too
  case "$stage" in
    unet|squeeze|squeeze_hall|squeeze_sky) cfg "$stage" >/dev/null ;;
    wide*|loso_hall*|loso_street*) cfg "squeeze_$stage" >/dev/null ;;
  esac
done
scripts/setup.sh
scripts/build.sh
data() {  # $1: data config name, $2: its output folder
  [ -f "$2/hypersim/metadata_images_split_scene_v1.csv" ] ||
    "$bin/infinisplat" generate --config "$(cfg "$1")"
}
for stage in "${stages[@]}"; do
  case "$stage" in
    unet|squeeze)
      data data out/depth_prior/data
      "$bin/infinisplat-train" --config "$(cfg $stage)" --resume auto ;;
    squeeze_hall|squeeze_sky)
      data data_hall out/depth_prior/data_hall
      "$bin/infinisplat-train" --config "$(cfg $stage)" --resume auto ;;
    wide|wide_aug|wide_w64|loso_hall|loso_hall_aug|loso_street_aug)
      data data_wide out/depth_prior/data_wide
      "$bin/infinisplat-train" --config "$(cfg squeeze_${stage})" --resume auto ;;
    wide_aug_clutter|loso_hall_aug_clutter|loso_hall_aug_clutter_long|loso_street_aug_clutter)
      data data_wide out/depth_prior/data_wide
      data data_clutter out/depth_prior/data_clutter
      "$bin/infinisplat-train" --config "$(cfg squeeze_${stage})" --resume auto ;;
    loso_trained_eval)
      # decoders trained on the held-out priors' depth (needs loso_hall_aug, loso_hall_aug_clutter, loso_street_aug
      # and loso_street_aug_clutter), scored on the held-out halls and streets and in the evaluation sets' format
      [ -f out/experiments/data/hypersim/metadata_images_split_scene_v1.csv ] ||
        "$bin/infinisplat" generate --config configs/recipe/data.json
      [ -d out/experiments/data_heldout_format/eval/hall_colmap ] ||
        "$bin/infinisplat" generate --config "$(cfg data_heldout_format)"
      for row in prior_trained_loso_aug_height prior_trained_loso_aug_clutter_height \
                 prior_trained_loso_street_aug_height prior_trained_loso_street_aug_clutter_height; do
        "$bin/infinisplat-experiment" --config configs/recipe/ablation.json --stage train --rows "$row" --seeds 0
      done
      # the clutter-trained halls decoder also with seed 1 (eval_prior_loso_hall_trained_s1)
      "$bin/infinisplat-experiment" --config configs/recipe/ablation.json --stage train \
        --rows prior_trained_loso_aug_clutter_height --seeds 1
      "$bin/infinisplat" eval-depth --config "$(cfg depth_eval_loso_street)"
      for c in eval_prior_loso_hall_trained eval_prior_loso_hall_trained_s1 eval_heldout_format \
               eval_prior_loso_street_trained; do
        "$bin/infinisplat-eval" --config "$(cfg $c)"
      done ;;
    loso_eval|loso_eval_flip|loso_eval_clutter|loso_eval_long)
      # end to end it scores the experiments' full_s0 (scripts/experiments.sh trains it)
      data data_wide out/depth_prior/data_wide
      "$bin/infinisplat" eval-depth --config "$(cfg depth_eval_loso_hall${stage#loso_eval})"
      "$bin/infinisplat-eval" --config "$(cfg eval_prior_loso_hall${stage#loso_eval})" ;;
    eval)
      [ -f out/experiments/data/hypersim/metadata_images_split_scene_v1.csv ] ||
        "$bin/infinisplat" generate --config configs/recipe/data.json
      # the "before" prior: the rooms-only net of the experiments (scripts/experiments.sh trains it too)
      "$bin/infinisplat-train" --config configs/recipe/depth.json --resume auto
      "$bin/infinisplat" eval-depth --config "$(cfg depth_eval)"
      "$bin/infinisplat" eval-depth --config "$(cfg depth_eval_height)"
      data data_wide out/depth_prior/data_wide
      "$bin/infinisplat" eval-depth --config "$(cfg depth_eval_dev)" ;;
    *) echo "train_depth_prior.sh: stage '$stage' is listed but has no recipe" >&2
       exit 2 ;;
  esac
done
echo "reports: out/depth_prior/eval/report.md, out/depth_prior/eval_height/report.md, out/depth_prior/dev/report.md"

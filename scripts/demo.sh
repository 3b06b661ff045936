#!/usr/bin/env bash
# The main job, end to end on the embedded default (no downloads): set up and build, generate the
# synthetic datasets, train the learned depth prior, train the quickstart model, evaluate it against its
# own initialization and the baselines, predict a scene from one photo, render an orbit video, and
# export ONNX. Everything lands under out/demo (OUT_DIR overrides).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
out="${OUT_DIR:-out/demo}"
bin="${BUILD_DIR:-$root/build}"
start=$(date +%s)
stamp() { echo; echo "== $1  ($(( $(date +%s) - start )) s elapsed)"; }
# A model run started with another model config (an earlier checkout's defaults) cannot resume: it moves aside,
# with the evaluation that scored it, and trains afresh. Nothing is lost.
set_aside_if_stale() {
  local dir="$1"
  shift
  [ -f "$dir/config.json" ] || return 0
  "$bin/infinisplat-train" "$@" --print-config >"$out/.config_now.json"
  if python3 -c 'import json, sys; a, b = (json.load(open(p))["model"] for p in sys.argv[1:]); sys.exit(a != b)' \
    "$dir/config.json" "$out/.config_now.json"; then
    return 0
  fi
  local aside
  aside="$out/previous-$(date +%Y%m%d-%H%M%S)"
  mkdir -p "$aside"
  mv "$dir" "$aside/"
  if [ -d "$out/eval" ]; then mv "$out/eval" "$aside/"; fi
  echo "demo.sh: $dir was trained with another model config (an earlier checkout's defaults); moved it and the" \
    "evaluation to $aside, training afresh"
}

stamp "1. set-up and build"
scripts/setup.sh
scripts/build.sh
mkdir -p "$out"
"$bin/infinisplat" version | tee "$out/version.txt"
if ! "$bin/infinisplat" weights >"$out/weights.txt"; then
  echo
  echo "NOTE: no pretrained weights found, so training runs without the perceptual term and the report gives LPIPS"
  echo "      as n/a. Everything else runs. To get them: scripts/get_weights.sh (see weights/README.md)."
fi

stamp "2. synthetic datasets (Hypersim layout for training; COLMAP and nerfstudio layouts for evaluation)"
if [ ! -f "$out/data/hypersim/metadata_images_split_scene_v1.csv" ]; then
  "$bin/infinisplat" generate --set generate.out="$out/data"
else
  echo "reusing $out/data"
fi

stamp "3. the learned depth prior (task: depth)"
"$bin/infinisplat-train" --config configs/depth_quickstart.json \
  --set data.hypersim.root="$out/data/hypersim" --set train.out="$out/depth" --resume auto

stamp "4. the quickstart model (ViT-S, the defaults: a support per pixel and at silhouettes, the dense head; 256x192, 1 context + 3 targets)"
quickstart=(--config configs/quickstart.json --set data.hypersim.root="$out/data/hypersim"
  --set train.out="$out/quickstart" --set model.prior.learned_weights="$out/depth/depth_net.safetensors")
set_aside_if_stale "$out/quickstart" "${quickstart[@]}"
"$bin/infinisplat-train" "${quickstart[@]}" --resume auto

stamp "4b. the same model with the paper's area sampling and implicit decoder (the defaults of config_version 2), to compare"
paper=(--config configs/quickstart_paper.json --set data.hypersim.root="$out/data/hypersim"
  --set train.out="$out/quickstart_paper" --set model.prior.learned_weights="$out/depth/depth_net.safetensors")
set_aside_if_stale "$out/quickstart_paper" "${paper[@]}"
"$bin/infinisplat-train" "${paper[@]}" --resume auto

stamp "5. evaluation: trained vs the paper's method vs step 0 vs baselines on the pair protocol (held-out rooms, then two other styles)"
"$bin/infinisplat-eval" --config configs/eval_synthetic.json \
  --set "datasets[0].root=$out/data/hypersim" \
  --set "datasets[1].root=$out/data/eval/courtyard_colmap" --set "datasets[2].root=$out/data/eval/atrium_nerfstudio" \
  --set "methods[0].checkpoint=$out/quickstart/checkpoints/last.safetensors" \
  --set "methods[1].checkpoint=$out/quickstart/checkpoints/last.safetensors" \
  --set "methods[2].checkpoint=$out/quickstart/checkpoints/init.safetensors" \
  --set "methods[3].checkpoint=$out/quickstart_paper/checkpoints/last.safetensors" \
  --set scoring.out="$out/eval" --set scoring.max_per_bin=4

stamp "6. one photo -> Gaussians (PLY) -> orbit video"
photo="$out/data/eval/courtyard_colmap/scene_0/images/IMG_0010.jpg"
"$bin/infinisplat" predict --checkpoint "$out/quickstart/checkpoints/last.safetensors" --image "$photo" \
  --out "$out/predict/scene.ply"
"$bin/infinisplat" render --ply "$out/predict/scene.ply" --trajectory orbit --frames 48 --depth --normal \
  --out "$out/predict/orbit"

stamp "7. ONNX export, checked in ONNX Runtime"
"$bin/infinisplat" export-onnx --checkpoint "$out/quickstart/checkpoints/last.safetensors" \
  --out "$out/export/model.onnx" --verify

stamp "done"
echo "report:        $out/eval/report.md (and .csv, .json, speed_quality.png)"
echo "training:      $out/quickstart (train_log.jsonl, val/*.png, checkpoints/)"
echo "scene + video: $out/predict/scene.ply, $out/predict/orbit/video.mp4"
echo "onnx:          $out/export/model.onnx"
echo
sed -n '/^## /,$p' "$out/eval/report.md" | grep -E "^## |\| (trained|trained-lidar|trained-paper|step0|lift|identity) \| all" || true
echo
echo "demo.sh: everything is under $(cd "$out" && pwd)"

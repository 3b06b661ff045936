#!/usr/bin/env bash
# 20 quickstart training steps from scratch with one build; prints the summary's mean step time.
bin=$1 out=$2
rm -rf "$out"
cd /work/main
"$bin/infinisplat-train" --config configs/quickstart.json --set data.hypersim.root=out/demo/data/hypersim \
  --set train.out="$out" --set train.steps=20 --set train.val_every=1000 --set train.checkpoint_every=1000 \
  --set model.prior.learned_weights=out/demo/depth/depth_net.safetensors > "$out.log" 2>&1
python3 -c "import json,sys; s=json.load(open('$out/summary.json')); print({k:v for k,v in s.items() if 'time' in k or 'ms' in k})"

#!/usr/bin/env bash
# 20 training steps of the ablation's full row (its stored config) from scratch with one build; prints step ms.
bin=$1 out=$2
rm -rf "$out"
cd /work/main
"$bin/infinisplat-train" --config out/experiments/ablation/runs/full_s0/config.json \
  --set train.out="$out" --set train.steps=20 --set train.val_every=1000 --set train.checkpoint_every=1000 > "$out.log" 2>&1 || { tail -5 "$out.log"; exit 1; }
python3 -c "
import json; s=json.load(open('$out/summary.json'))['mean_step_time_ms']
print('total %.0f' % sum(v for k,v in s.items() if k!='render_bwd'), {k: round(v) for k,v in s.items()})"

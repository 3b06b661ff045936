#!/usr/bin/env bash
# The demo's evaluation (scripts/demo.sh step 5, on its out/demo data), 2 pairs per bin, with one build's
# infinisplat-eval. Usage: eval_cmp.sh BUILD_DIR OUT_DIR (run from anywhere; the data must exist from a demo run).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
bin=$1 out=$2 o=$root/out/demo
cd "$root"
/usr/bin/time -f "wall %e s, peak %M KB" "$bin/infinisplat-eval" --config configs/eval_synthetic.json \
  --set "datasets[0].root=$o/data/hypersim" \
  --set "datasets[1].root=$o/data/eval/courtyard_colmap" --set "datasets[2].root=$o/data/eval/atrium_nerfstudio" \
  --set "methods[0].checkpoint=$o/quickstart/checkpoints/last.safetensors" \
  --set "methods[1].checkpoint=$o/quickstart/checkpoints/last.safetensors" \
  --set "methods[2].checkpoint=$o/quickstart/checkpoints/init.safetensors" \
  --set scoring.out="$out" --set scoring.max_per_bin=2

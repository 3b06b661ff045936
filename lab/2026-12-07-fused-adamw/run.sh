#!/usr/bin/env bash
# Training steps before and after the one-pass AdamW, alternating in fresh processes.
# Usage: run.sh OLD_BENCH_TRAIN_STEP NEW_BENCH_TRAIN_STEP ROUNDS OUT (from the checkout's root: the configs are read there)
set -euo pipefail
old=$1 new=$2 rounds=$3 out=$4
: >"$out"
for r in $(seq 1 "$rounds"); do
  for config in configs/recipe/recipe.json configs/quickstart.json; do
    for side in old new; do
      bin=$old
      [[ $side == new ]] && bin=$new
      figures=$("$bin" "" 0 "$config" 2>/dev/null | awk '$1 == "optim" || $1 == "total" {printf "%s %s ", $1, $2}')
      echo "round $r $config $side $figures" | tee -a "$out"
    done
  done
done

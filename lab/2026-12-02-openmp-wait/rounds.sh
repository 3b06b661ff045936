#!/usr/bin/env bash
# Alternating rounds of bench_predict and bench_train_step for two builds (fresh processes, A then B each round).
# Usage: rounds.sh ROUNDS FILE NAME_A BUILD_DIR_A NAME_B BUILD_DIR_B [ENV_A] [ENV_B]
# ENV_A/ENV_B: an environment assignment for that build's runs (e.g. GOMP_SPINCOUNT=300000), or X=1 for none.
set -euo pipefail
[ $# -ge 6 ] || { echo "usage: $0 ROUNDS FILE NAME_A BUILD_A NAME_B BUILD_B [ENV_A] [ENV_B]" >&2; exit 2; }
rounds=$1 file=$2 name_a=$3 dir_a=$4 name_b=$5 dir_b=$6 env_a=${7:-X=1} env_b=${8:-X=1}
root="$(cd "$(dirname "$0")/../.." && pwd)"
for r in $(seq 1 "$rounds"); do
  for side in a b; do
    if [ $side = a ]; then name=$name_a dir=$dir_a e=$env_a; else name=$name_b dir=$dir_b e=$env_b; fi
    echo "## round $r $name predict ($e)"
    env "$e" "$dir/bench_predict" --runs 3 | grep -v '^predict'
    echo "## round $r $name train ($e)"
    env "$e" "$dir/bench_train_step" "" 0 "$root/configs/recipe/recipe.json" 2>&1 | grep -E '^  [a-z_]+ +[0-9.]+$'
  done
done > "$file"

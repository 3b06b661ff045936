#!/usr/bin/env bash
cd /work/main
for r in $(seq 1 $1); do
  for e in ${VARIANTS:-"GOMP_SPINCOUNT=0" "GOMP_SPINCOUNT=3000" "GOMP_SPINCOUNT=10000" "GOMP_SPINCOUNT=30000"}; do
    n=${e#GOMP_SPINCOUNT=}
    echo "## round $r spin$n predict"; env $e ./build/bench_predict --runs 3 | grep -v '^predict'
    echo "## round $r spin$n train"; env $e ./build/bench_train_step "" 0 configs/recipe/recipe.json 2>&1 | grep -E '^  [a-z_]+ +[0-9.]+$'
  done
done

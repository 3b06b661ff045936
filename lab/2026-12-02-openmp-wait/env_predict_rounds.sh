#!/usr/bin/env bash
# rounds of bench_predict under three waits
for r in $(seq 1 $1); do
  for e in "X=1" "OMP_WAIT_POLICY=passive" "GOMP_SPINCOUNT=10000"; do
    echo "## round $r $e"
    env $e /work/main/build/bench_predict --runs 3 | grep -v '^predict'
  done
done

#!/usr/bin/env bash
# env_rounds.sh ROUNDS FILTER CMD... : alternate the command under each wait setting, fresh processes
rounds=$1 filter=$2; shift 2
for r in $(seq 1 $rounds); do
  for e in "X=1" "OMP_WAIT_POLICY=passive"; do
    echo "## round $r $e"
    env $e "$@" 2>&1 | grep -E "$filter"
  done
done

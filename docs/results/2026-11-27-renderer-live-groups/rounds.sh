#!/usr/bin/env bash
# The report's alternating rounds: bench_render from before the change (cf2ff98) and after it (4fb9a04), each
# in a fresh process with nothing else running. OLD and NEW are the two binaries; the logs go to OUT.
set -euo pipefail
OLD=${OLD:-/tmp/rr/bench_old}
NEW=${NEW:-/tmp/rr/bench_new}
OUT=${OUT:-$(dirname "$0")}
run() {  # run ROUNDS FILE ARGS...: ROUNDS alternating rounds of old and new
  local rounds=$1 file=$2
  shift 2
  for r in $(seq 1 "$rounds"); do
    for b in old new; do
      local bin=$OLD
      [ "$b" = new ] && bin=$NEW
      echo "## round $r $b $*"
      "$bin" "$@" | grep '^| [0-9]'
    done
  done > "$OUT/$file"
}
run 6 only_100k_rounds.txt --only 100k
run 3 quick_rounds.txt --quick
run 3 avx2_100k_rounds.txt --only 100k --simd avx2

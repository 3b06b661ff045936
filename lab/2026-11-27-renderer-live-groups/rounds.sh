#!/usr/bin/env bash
# The report's alternating rounds, each binary in a fresh process with nothing else running. OLD: bench_render
# built from cf2ff98 (before the change); NEW: built from 4fb9a04 (after it); EXP: 4fb9a04 with narrow Gaussians
# run as whole-row jobs in the AVX-512 backward (`if (g1 - g0 == 2)` -> `if (true)` in bwd_tile_avx512), an
# experiment not kept. The logs go to OUT; set A ran first (22:22-22:25 UTC), set B after it.
set -euo pipefail
OLD=${OLD:-/tmp/rr/bench_old}
NEW=${NEW:-/tmp/rr/bench_new}
EXP=${EXP:-/tmp/rr/bench_exp}
MID=${MID:-/tmp/rc/bench_mid}  # d2f9c9a (the change, after review), for the addendum's sets
ALIGNED=${ALIGNED:-/tmp/rc/bench_new}  # 414c065 (aligned scratch)
OUT=${OUT:-$(dirname "$0")}
run() {  # run ROUNDS FILE "BINARIES" ARGS...: ROUNDS rounds, each running the named binaries in turn
  local rounds=$1 file=$2 names=$3
  shift 3
  for r in $(seq 1 "$rounds"); do
    for b in $names; do
      local bin=$OLD
      [ "$b" = new ] && bin=$NEW
      [ "$b" = exp ] && bin=$EXP
      [ "$b" = mid ] && bin=$MID
      [ "$b" = aligned ] && bin=$ALIGNED
      echo "## round $r $b $*"
      "$bin" "$@" | grep '^| [0-9]'
    done
  done > "$OUT/$file"
}
run 6 only_100k_rounds_a.txt "old new" --only 100k
run 3 quick_rounds_a.txt "old new" --quick
run 3 avx2_100k_rounds.txt "old new" --only 100k --simd avx2
run 6 only_100k_rounds_b.txt "old new exp" --only 100k
run 3 quick_rounds_b.txt "old new" --quick
# The addendum. Its logs name the binaries old / mid / new; here new is ALIGNED, and the first two sets ran mid
# as "old" against ALIGNED as "new".
OLD_CF=$OLD
OLD=$MID NEW=$ALIGNED run 6 aligned_only_100k_rounds.txt "old new" --only 100k
OLD=$MID NEW=$ALIGNED run 3 aligned_quick_rounds.txt "old new" --quick
OLD=$OLD_CF NEW=$ALIGNED run 6 only_100k_rounds_c.txt "old mid new" --only 100k
OLD=$OLD_CF NEW=$ALIGNED run 3 quick_rounds_c.txt "old mid new" --quick

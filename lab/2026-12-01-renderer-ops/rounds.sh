#!/usr/bin/env bash
# The report's alternating rounds, each binary in a fresh process. OLD: bench_render with the kernels of 4bba2b0
# (before this change) and the --stat option of ed6f245's bench; NEW: bench_render built at ed6f245 (after it).
# Usage: OLD=... NEW=... rounds.sh [OUT]; the logs go to OUT (default: this folder).
set -euo pipefail
OLD=${OLD:-/tmp/bench_render_old}
NEW=${NEW:-/tmp/bench_render_final2}
OUT=${1:-$(dirname "$0")}
run() {  # run ROUNDS FILE ARGS...: ROUNDS rounds of old then new
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
run 8 only_100k_min.txt --only 100k --runs-scale 3 --stat min
run 8 only_100k_median.txt --only 100k --runs-scale 3
run 3 quick_min.txt --quick --stat min
run 3 avx2_100k_min.txt --only 100k --runs-scale 3 --stat min --simd avx2

#!/usr/bin/env bash
# Alternating rounds of two bench_render binaries, each in a fresh process: OLD (481fa9f, before the projection's
# vector tail) and NEW (the binary under test). Usage: OLD=... NEW=... rounds.sh [OUT]; logs go to OUT (default: this
# folder). Each log has "## round N old|new ARGS" headers, which summary.py --names old new reads.
set -euo pipefail
OLD=${OLD:-/tmp/bench_render_base}
NEW=${NEW:-/tmp/bench_render_new}
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
run 10 only_100k_min.txt --only 100k --runs-scale 3 --stat min
run 6 only_100k_median.txt --only 100k --runs-scale 3
run 3 quick_min.txt --quick --stat min

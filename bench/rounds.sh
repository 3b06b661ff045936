#!/usr/bin/env bash
# Alternating benchmark rounds: two bench_render binaries, each in a fresh process, so that a busy machine slows
# both alike. Usage: bench/rounds.sh ROUNDS FILE NAME_A BIN_A NAME_B BIN_B [BENCH ARGS...]
# Writes to FILE the table rows of each run under "## round N NAME ARGS" headers, which
# bench/rounds_summary.py --names NAME_A NAME_B reads.
set -euo pipefail
[ $# -ge 6 ] || { echo "usage: $0 ROUNDS FILE NAME_A BIN_A NAME_B BIN_B [BENCH ARGS...]" >&2; exit 2; }
rounds=$1 file=$2 name_a=$3 bin_a=$4 name_b=$5 bin_b=$6
shift 6
for bin in "$bin_a" "$bin_b"; do [ -x "$bin" ] || { echo "$0: no executable $bin" >&2; exit 2; }; done
for r in $(seq 1 "$rounds"); do
  echo "## round $r $name_a $*"
  "$bin_a" "$@" | grep '^| [0-9]'
  echo "## round $r $name_b $*"
  "$bin_b" "$@" | grep '^| [0-9]'
done > "$file"

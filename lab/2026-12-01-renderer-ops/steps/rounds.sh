#!/usr/bin/env bash
# run ROUNDS FILE "names" ARGS: the binaries /tmp/bench_render_<name> in turn, each in a fresh process (steps/*.txt: ROUNDS 5 or 6, ARGS --only 100k --runs-scale 3 --stat min)
rounds=$1; file=$2; names=$3; shift 3
for r in $(seq 1 "$rounds"); do for b in $names; do echo "## round $r $b $*"; /tmp/bench_render_$b "$@" | grep '^| [0-9]'; done; done > "$file"

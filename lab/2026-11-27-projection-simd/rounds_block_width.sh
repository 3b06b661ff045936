#!/bin/bash
# The block-width rounds: the scalar projection (264b064), 16-lane blocks (e877207) and register-wide blocks
# (17b6458), in turn, each in a fresh process. OLD, NEW and L8 are the three bench_render binaries.
OLD=${OLD:-/tmp/bench_render_old}
NEW=${NEW:-/tmp/bench_render_new}
L8=${L8:-/tmp/bench_render_l8}
# shellcheck disable=SC2016  # awk programs, not shell expansions
cols='{print "first",$7,"fwd",$8,"fb",$9,"proj",$11,"bin",$12,"rast",$13,"rbwd",$14,"pbwd",$15,"peakF",$16,"peakFB",$17}'
# shellcheck disable=SC2016
cols_phases='{print "first",$7,"fwd",$8,"fb",$9,"proj",$11,"bin",$12,"rast",$13,"rbwd",$14,"pbwd",$15}'
run() { case $1 in old) echo "$OLD" ;; new) echo "$NEW" ;; l8) echo "$L8" ;; esac; }
for r in 1 2 3 4; do  # block_width_100k_rounds.txt
  for b in old new l8; do
    echo -n "$b "; "$(run $b)" --only 100k 2>&1 | tail -1 | awk -F'|' "$cols"
  done
done
for r in 1 2; do  # block_width_levels_rounds.txt (portable: one round)
  for lvl in avx2 portable; do
    [ $lvl = portable ] && [ $r = 2 ] && continue
    for b in old new l8; do
      echo -n "$lvl $b "; "$(run $b)" --only 100k --simd $lvl 2>&1 | tail -1 | awk -F'|' "$cols_phases"
    done
  done
done

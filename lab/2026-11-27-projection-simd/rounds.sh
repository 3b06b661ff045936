#!/bin/bash
# The alternating rounds of the report: the binary from before the change (264b064) and after it (e877207),
# each in a fresh process, nothing else running. OLD and NEW are the two bench_render binaries.
OLD=${OLD:-/tmp/bench_render_old}
NEW=${NEW:-/tmp/bench_render_new}
# shellcheck disable=SC2016  # awk programs, not shell expansions
cols='{print "first",$7,"fwd",$8,"fb",$9,"proj",$11,"bin",$12,"rast",$13,"rbwd",$14,"pbwd",$15,"peakF",$16,"peakFB",$17}'
# shellcheck disable=SC2016
cols_phases='{print "first",$7,"fwd",$8,"fb",$9,"proj",$11,"bin",$12,"rast",$13,"rbwd",$14,"pbwd",$15}'
for r in 1 2 3 4 5; do  # quick_rounds.txt
  for b in old new; do
    echo "## round $r $b"
    bin=$OLD; [ $b = new ] && bin=$NEW
    "$bin" --quick 2>&1 | grep '^| [0-9]'
  done
done
for r in 1 2 3 4 5 6; do  # only_100k_rounds.txt
  for b in old new; do
    bin=$OLD; [ $b = new ] && bin=$NEW
    echo -n "$b "; "$bin" --only 100k 2>&1 | tail -1 | awk -F'|' "$cols"
  done
done
for r in 1 2 3; do  # levels_100k_rounds.txt (portable: two rounds)
  for lvl in avx2 portable; do
    [ $lvl = portable ] && [ $r = 3 ] && continue
    for b in old new; do
      bin=$OLD; [ $b = new ] && bin=$NEW
      echo -n "$lvl $b "; "$bin" --only 100k --simd $lvl 2>&1 | tail -1 | awk -F'|' "$cols_phases"
    done
  done
done

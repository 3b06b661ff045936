#!/usr/bin/env bash
# This report's rounds: OLD (bench_render of 481fa9f, before the projection's vector tail) against NEW (the binary
# under test), each in a fresh process, through bench/rounds.sh. Usage: OLD=... NEW=... rounds.sh [OUT]; logs go to
# OUT (default: this folder).
set -euo pipefail
OLD=${OLD:-/tmp/bench_render_base}
NEW=${NEW:-/tmp/bench_render_new}
OUT=${1:-$(dirname "$0")}
rounds="$(dirname "$0")/../../bench/rounds.sh"
"$rounds" 10 "$OUT/only_100k_min.txt" old "$OLD" new "$NEW" --only 100k --runs-scale 3 --stat min
"$rounds" 6 "$OUT/only_100k_median.txt" old "$OLD" new "$NEW" --only 100k --runs-scale 3
"$rounds" 3 "$OUT/quick_min.txt" old "$OLD" new "$NEW" --quick --stat min

#!/usr/bin/env bash
# Fails when a folder under src/ includes a folder that comes later in the data flow (README, "What is here").
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
order=(core geometry io nets data prior sampler encoder decoder model render loss metrics predict export)
rank() { local i; for i in "${!order[@]}"; do [ "${order[$i]}" = "$1" ] && { echo "$i"; return; }; done; echo -1; }
bad=0
for dir in "$root"/src/*/; do
  from=$(basename "$dir")
  rf=$(rank "$from")
  [ "$rf" -ge 0 ] || { echo "check_layers: src/$from is not in the layer order; add it to scripts/check_layers.sh" >&2; bad=1; continue; }
  while IFS= read -r line; do
    file=${line%%:*}
    to=$(sed -n 's/.*#include "\([a-z_]*\)\/.*/\1/p' <<<"${line#*:}")
    [ -n "$to" ] || continue
    rt=$(rank "$to")
    [ "$rt" -ge 0 ] || continue  # not a src/ folder
    if [ "$rt" -gt "$rf" ]; then
      echo "check_layers: ${file#"$root"/} ($from) includes $to, which comes later in the data flow" >&2
      bad=1
    fi
  done < <(grep -rn '#include "' "$dir" || true)
done
[ "$bad" -eq 0 ] && echo "check_layers: src/ includes only earlier layers (${order[*]})"
exit "$bad"

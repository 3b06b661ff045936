#!/usr/bin/env bash
# Configures and builds the project (Release, Ninja, ccache when present) into build/.
# Usage: scripts/build.sh [extra cmake args...]; BUILD_DIR and JOBS override the defaults.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
jobs="${JOBS:-$(nproc)}"
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@"
elif [ $# -gt 0 ]; then
  cmake "$build" "$@"
fi
start=$(date +%s)
cmake --build "$build" -j "$jobs"
echo "build.sh: built in $(( $(date +%s) - start )) s -> $build"

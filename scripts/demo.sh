#!/usr/bin/env bash
# The main job, end to end on the embedded default: set up, build, then run every stage that exists.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${OUT_DIR:-$root/out/demo}"
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
bin="${BUILD_DIR:-$root/build}"
mkdir -p "$out"

echo "== 1. runtime check"
"$bin/infinisplat" version | tee "$out/version.txt"

echo
echo "demo.sh: everything is under $out"

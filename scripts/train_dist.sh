#!/usr/bin/env bash
# Data-parallel training on one machine: starts N ranks of infinisplat-train (each with its share of the
# cores) that rendezvous through a TCPStore on rank 0, and stops them all if one fails.
#   scripts/train_dist.sh N config.json [infinisplat-train options, e.g. --set train.steps=100 --resume auto]
# Several machines: start one rank per process on each machine with the same MASTER_ADDR (rank 0's
# address, reachable by all), MASTER_PORT and WORLD_SIZE, and RANK = 0..WORLD_SIZE-1, e.g. on machine B:
#   RANK=1 WORLD_SIZE=2 MASTER_ADDR=10.0.0.1 MASTER_PORT=29500 GLOO_SOCKET_IFNAME=eth0 \
#     build/infinisplat-train --config config.json --threads 2
# The run folder (train.out) must be the same path on every machine for resuming (a shared folder), and only
# rank 0 writes into it.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${BUILD_DIR:-$root/build}/infinisplat-train"
[ $# -ge 2 ] || { echo "usage: scripts/train_dist.sh N config.json [infinisplat-train options]" >&2; exit 2; }
n="$1"; config="$2"; shift 2
[[ "$n" =~ ^[1-9][0-9]*$ ]] || { echo "train_dist.sh: N must be a positive integer, got '$n'" >&2; exit 2; }
[ -x "$bin" ] || { echo "train_dist.sh: $bin not built (scripts/build.sh)" >&2; exit 1; }
threads=$(( $(nproc) / n )); [ "$threads" -ge 1 ] || threads=1
port="${MASTER_PORT:-$(( 20000 + RANDOM % 20000 ))}"
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap 'cleanup; exit 130' INT TERM
for (( r = 0; r < n; r++ )); do
  RANK=$r WORLD_SIZE=$n MASTER_ADDR="${MASTER_ADDR:-127.0.0.1}" MASTER_PORT=$port \
    "$bin" --config "$config" --threads "$threads" "$@" &
  pids+=($!)
done
status=0
# The first rank to fail stops the others (they would otherwise wait for it until the timeout).
while [ ${#pids[@]} -gt 0 ]; do
  if wait -n "${pids[@]}"; then :; else rc=$?; [ "$status" -ne 0 ] || status=$rc; cleanup; fi
  alive=()
  for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive+=("$p"); done
  pids=("${alive[@]+"${alive[@]}"}")
done
exit "$status"

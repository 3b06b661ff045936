#!/usr/bin/env bash
# Data-parallel throughput on this machine: the same global batch trained as 1 rank x all cores and as
# N ranks x (cores / N) threads, on the experiment recipe; prints tuples per second, the all-reduce time per
# step and the gradient bytes each rank exchanges per step (what a second machine's link must carry).
#   scripts/bench_dist.sh [steps=20] [ranks=2] [config=configs/recipe/recipe.json]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
steps="${1:-20}"; ranks="${2:-2}"; config="${3:-configs/recipe/recipe.json}"
bin="${BUILD_DIR:-$root/build}"
out="$(mktemp -d /tmp/bench_dist.XXXXXX)"
common=(--set "train.steps=$steps" --set train.val_every=100000 --set train.checkpoint_every=100000 --set data.workers=1)
cores=$(nproc)
echo "bench_dist: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $cores cores, $steps steps, config $config"
"$bin/infinisplat-train" --config "$config" "${common[@]}" --set "data.batch_size=$ranks" \
  --set "train.out=$out/one" --threads "$cores" > "$out/one.log" 2>&1
scripts/train_dist.sh "$ranks" "$config" "${common[@]}" --set data.batch_size=1 --set "train.out=$out/many" \
  > "$out/many.log" 2>&1
python3 - "$out" "$ranks" "$cores" <<'PY'
import json, sys
out, ranks, cores = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def stats(run, global_batch):
    recs = [json.loads(l) for l in open(f"{out}/{run}/train_log.jsonl") if '"loss"' in l]
    recs = recs[2:] or recs  # the first steps warm up allocators and the loader
    ms = sum(r["step_ms"] for r in recs) / len(recs)
    ar = sum(r["time_ms"].get("allreduce", 0) for r in recs) / len(recs)
    return ms, global_batch * 1000.0 / ms, ar
ms1, tps1, _ = stats("one", ranks)
msn, tpsn, ar = stats("many", ranks)
import struct
with open(f"{out}/many/checkpoints/init.safetensors", "rb") as f:
    n = struct.unpack("<Q", f.read(8))[0]
    header = json.loads(f.read(n))
import math
floats = sum(math.prod(v["shape"]) for k, v in header.items() if k.startswith("model/") and v["dtype"] == "F32")
mb = floats * 4 / 1e6
print(f"| setup | step (ms) | tuples/s | all-reduce per step (ms) |")
print(f"|---|---|---|---|")
print(f"| 1 rank x {cores} threads, batch {ranks} | {ms1:.0f} | {tps1:.2f} | - |")
print(f"| {ranks} ranks x {max(1, cores // ranks)} thread(s), batch 1 each | {msn:.0f} | {tpsn:.2f} | {ar:.1f} |")
print(f"gradients: {floats} floats = {mb:.1f} MB per rank per step; a ring all-reduce sends and receives "
      f"2(N-1)/N of that per rank: {2 * (ranks - 1) / ranks * mb:.1f} MB per step at N={ranks}, so a second machine "
      f"on a 1 Gbit/s link adds about {2 * (ranks - 1) / ranks * mb * 8 / 1000 * 1000:.0f} ms per step")
PY

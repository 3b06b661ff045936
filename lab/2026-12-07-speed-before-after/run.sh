#!/usr/bin/env bash
# Issue 72's baseline against today's tree, alternating in one run on one machine. With --avx2, both run their
# AVX2-only code paths: LibTorch's kernels capped at AVX2 (ATEN_CPU_CAPABILITY), oneDNN capped at AVX2
# (ONEDNN_MAX_CPU_ISA), the renderer's AVX2 loops (--simd avx2; the training step's renderer keeps the CPU's best,
# the same code in both trees), OpenBLAS on its Haswell kernels (the environment's pin). Without it, each runs what
# the CPU has, and today's tree also runs bf16.
# Usage: run.sh [--avx2] BASE_TREE HEAD_TREE OUT_DIR [rounds] [--paper]
# Each tree holds its checkout's configs and its Release build in build/ (BASE_BUILD, HEAD_BUILD: other names).
set -euo pipefail
avx2=0
[[ "${1:-}" == --avx2 ]] && avx2=1 && shift
base=$1 head=$2 out=$3 rounds=${4:-3} paper=${5:-}
export OPENBLAS_CORETYPE=Haswell
simd=()
if ((avx2)); then
  export ATEN_CPU_CAPABILITY=avx2 ONEDNN_MAX_CPU_ISA=AVX2
  simd=(--simd avx2)
fi
mkdir -p "$out"
log() { echo "== $(date -u +%H:%M:%S) $*" | tee -a "$out/rounds.txt"; }
run() {  # run LABEL TREE BINARY ARGS...
  local label=$1 tree=$2 bin=$3 sub=${BASE_BUILD:-build}
  [[ "$tree" == "$head" ]] && sub=${HEAD_BUILD:-build}
  shift 3
  log "$label: $bin $*"
  (cd "$tree" && "$sub/$bin" "$@") >>"$out/rounds.txt" 2>&1
}
# fp32 is today's default, and what `auto` gives on a CPU without AVX512-BF16 or AMX.
head_precisions=(fp32)
((avx2)) || head_precisions=(fp32 bf16)
for r in $(seq 1 "$rounds"); do
  run "round $r base" "$base" bench_predict --runs 5
  for p in "${head_precisions[@]}"; do run "round $r head $p" "$head" bench_predict --runs 5 --precision "$p"; done
  run "round $r base" "$base" bench_train_step "" 0 configs/recipe/recipe.json
  run "round $r head" "$head" bench_train_step "" 0 configs/recipe/paper.json --precision fp32
  run "round $r head" "$head" bench_train_step "" 0 configs/recipe/recipe.json --precision fp32
  run "round $r base" "$base" bench_train_step "" 0 configs/quickstart.json
  run "round $r head" "$head" bench_train_step "" 0 configs/quickstart_paper.json --precision fp32
  run "round $r head" "$head" bench_train_step "" 0 configs/quickstart.json --precision fp32
  for size in 20k 100k; do
    run "round $r base" "$base" bench_render "${simd[@]}" --only "$size" --stat min
    run "round $r head" "$head" bench_render "${simd[@]}" --only "$size" --stat min
  done
done
if [[ "$paper" == --paper ]]; then
  run "paper base" "$base" bench_predict --paper --runs 1
  for p in "${head_precisions[@]}"; do run "paper head $p" "$head" bench_predict --paper --runs 1 --precision "$p"; done
fi
log done

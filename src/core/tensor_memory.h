// Live CPU tensor memory: a counting wrapper around LibTorch's CPU allocator, so the memory one prediction needs can
// be read apart from what the process keeps resident (freed memory stays mapped for reuse: core/runtime).
#pragma once
#include <cstdint>

namespace isplat {

// Makes every CPU tensor allocated from now on counted (idempotent). Tensors allocated before are never counted, nor
// are their frees. It stays installed for the life of the process. Call it first thing in main(), before any tensor
// exists: oneDNN frees its buffers through whichever CPU allocator is current, so swapping allocators while such a
// buffer lives would hand it to the wrong one. The executables that report working memory call it (infinisplat-eval,
// infinisplat-experiment, the tests); the others keep LibTorch's allocator untouched.
void count_tensor_memory();
bool tensor_memory_counted();

// Bytes of counted CPU tensor memory allocated and not yet freed.
int64_t live_tensor_bytes();
// Restarts the peak from the live bytes now; peak_tensor_bytes() is then the largest live total since.
void reset_tensor_peak();
int64_t peak_tensor_bytes();

}  // namespace isplat

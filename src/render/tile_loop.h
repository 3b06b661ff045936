// Internal to the render kernels: the parallel loop over 16×16 tiles and its per-thread scratch.
#pragma once
#include <ATen/Parallel.h>

#include <atomic>
#include <cstring>
#include <vector>

#include "render/kernels.h"

namespace isplat::splat {

// Per-thread buffers reused across the tiles a thread renders.
template <class T>
struct TileScratch {
  std::vector<T> records, state;
  int32_t last[kTile * kTile];
  uint8_t done[kTile * kTile];

  // The tile's records gathered into one contiguous array, in list order (cache friendly).
  const T* gather(const T* packed, const int32_t* ids, int64_t count) {
    records.resize(size_t(std::max<int64_t>(count, 1) * kRec));
    for (int64_t i = 0; i < count; ++i)
      std::memcpy(records.data() + i * kRec, packed + int64_t(ids[i]) * kRec, sizeof(T) * kRec);
    return records.data();
  }
  T* pixel_state(int stride) {
    state.resize(size_t(kTile * kTile * stride));
    return state.data();
  }
};

// Calls fn(tile, x0, y0, x1, y1, scratch) for every tile, pixels [x0, x1) × [y0, y1). Threads claim tiles
// from a shared counter, which balances uneven tiles; a tile's result never depends on which thread ran it.
template <class T, class Fn>
void for_each_tile(const CameraParams& cam, Fn&& fn) {
  const int64_t tiles_x = cam.tiles_x(), tiles = tiles_x * cam.tiles_y();
  std::atomic<int64_t> next{0};
  const int64_t workers = std::max<int64_t>(1, std::min<int64_t>(at::get_num_threads(), tiles));
  at::parallel_for(0, workers, 1, [&](int64_t, int64_t) {
    TileScratch<T> scratch;
    for (int64_t t = next.fetch_add(1, std::memory_order_relaxed); t < tiles;
         t = next.fetch_add(1, std::memory_order_relaxed)) {
      const int64_t x0 = (t % tiles_x) * kTile, y0 = (t / tiles_x) * kTile;
      fn(t, x0, y0, std::min(x0 + kTile, cam.width), std::min(y0 + kTile, cam.height), scratch);
    }
  });
}

}  // namespace isplat::splat

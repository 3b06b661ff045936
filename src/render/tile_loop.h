// Internal to the render kernels: the parallel loop over 16×16 tiles, per-thread scratch and a Gaussian's pixel box.
#pragma once
#include <ATen/Parallel.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <new>
#include <vector>

#include "render/kernels.h"
#include "render/lanes.h"

namespace isplat::splat {

// floor for values already clamped to a small range.
ISPLAT_INLINE int64_t ifloor(double x) {
  const int64_t i = int64_t(x);
  return i - (double(i) > x);
}

// The rows [ys, ye) and lane groups [g0, g1) of tile (x0, y0, x1, y1) that the record's box may cover.
template <class T>
ISPLAT_INLINE bool pixel_box(const T* rec, int64_t x0, int64_t y0, int64_t x1, int64_t y1, int64_t& ys, int64_t& ye,
                             int64_t& g0, int64_t& g1) {
  // Pixel centre c = p + 0.5 lies in [m − r, m + r]  <=>  p in [m − r − 0.5, m + r − 0.5].
  auto lo = [](double m, double r, int64_t a) { return std::max<int64_t>(a, ifloor(std::max(m - r - 0.5, a - 1.0))); };
  auto hi = [](double m, double r, int64_t b) {
    return std::min<int64_t>(b, ifloor(std::min(m + r - 0.5, b + 1.0)) + 1);
  };
  const double u = rec[kU], v = rec[kV], rx = rec[kRx], ry = rec[kRy];
  ys = lo(v, ry, y0), ye = hi(v, ry, y1);
  const int64_t xs = lo(u, rx, x0), xe = hi(u, rx, x1);
  if (ys >= ye || xs >= xe) return false;
  g0 = (xs - x0) / kLanes, g1 = (xe - 1 - x0) / kLanes + 1;
  return true;
}

// Copies one tile row of w ≤ kTile values. A full row (the common case) has a size known at compile time, so the
// copy is a few vector moves instead of a call to memmove (7 calls per row in the backward's set-up).
template <class V>
ISPLAT_INLINE void copy_row(const V* src, int64_t w, V* dst) {
  if (w == kTile)
    std::memcpy(dst, src, sizeof(V) * kTile);
  else
    std::memcpy(dst, src, sizeof(V) * size_t(w));
}

// An allocator of 64-byte aligned storage: a tile row's plane (16 floats) is then one cache line, so vector loads
// and stores of it never straddle two lines, and a gathered float record is one line too. (malloc aligns to 16.)
template <class V>
struct LineAligned {
  using value_type = V;
  LineAligned() = default;
  template <class U>
  LineAligned(const LineAligned<U>&) {}
  V* allocate(size_t n) { return static_cast<V*>(::operator new(n * sizeof(V), std::align_val_t(64))); }
  void deallocate(V* p, size_t) { ::operator delete(p, std::align_val_t(64)); }
  template <class U>
  bool operator==(const LineAligned<U>&) const {
    return true;
  }
  template <class U>
  bool operator!=(const LineAligned<U>&) const {
    return false;
  }
};
template <class V>
using LineVector = std::vector<V, LineAligned<V>>;

// Per-thread buffers reused across the tiles a thread renders.
template <class T>
struct TileScratch {
  LineVector<T> records, state;
  LineVector<int32_t> last = LineVector<int32_t>(kPix);

  // The tile's records gathered into one contiguous array, in list order (cache friendly).
  const T* gather(const T* packed, const int32_t* ids, int64_t count) {
    records.resize(size_t(std::max<int64_t>(count, 1) * kRec));
    constexpr int64_t kAhead = 8;  // records requested ahead: the reads are random, so their misses overlap
    for (int64_t i = 0; i < std::min(count, kAhead); ++i) __builtin_prefetch(packed + int64_t(ids[i]) * kRec);
    for (int64_t i = 0; i < count; ++i) {
      if (i + kAhead < count) __builtin_prefetch(packed + int64_t(ids[i + kAhead]) * kRec);
      std::memcpy(records.data() + i * kRec, packed + int64_t(ids[i]) * kRec, sizeof(T) * kRec);
    }
    return records.data();
  }
  // Per-pixel state: `planes` values per pixel, laid out as fwd_at / bwd_at say.
  T* pixel_planes(int planes) {
    state.resize(size_t(kPix * planes));
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

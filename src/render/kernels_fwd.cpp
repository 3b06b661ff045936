// Tile binning (compaction with tile counts, depth sort, offsets, fill) and front-to-back rasterization.
#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "core/error.h"
#include "render/kernels.h"
#include "render/lanes_avx512.h"
#include "render/tile_loop.h"

namespace isplat::splat {
namespace {

// A buffer of n values left uninitialized (std::vector would zero it first).
template <class V>
std::unique_ptr<V[]> uninit(int64_t n) {
  return std::unique_ptr<V[]>(new V[size_t(std::max<int64_t>(n, 1))]);
}

// Stable LSD radix sort of n (key, value) pairs by key, 8 bits per pass. All passes' histograms come from one
// read; a pass whose digit is the same for every key is skipped.
template <class K>
void radix_sort(K* keys, int32_t* vals, int64_t n) {
  constexpr int kPasses = int(sizeof(K));
  std::array<std::array<int64_t, 256>, kPasses> count{};
  for (int64_t i = 0; i < n; ++i)
    for (int d = 0; d < kPasses; ++d) ++count[d][(keys[i] >> (8 * d)) & 0xff];
  auto k2 = uninit<K>(n);
  auto v2 = uninit<int32_t>(n);
  K* kin = keys;
  int32_t* vin = vals;
  K* kout = k2.get();
  int32_t* vout = v2.get();
  for (int d = 0; d < kPasses; ++d) {
    auto& c = count[d];
    if (n == 0 || c[(kin[0] >> (8 * d)) & 0xff] == n) continue;
    int64_t sum = 0;
    for (auto& x : c) sum += std::exchange(x, sum);
    for (int64_t i = 0; i < n; ++i) {
      const int64_t at = c[(kin[i] >> (8 * d)) & 0xff]++;
      kout[at] = kin[i], vout[at] = vin[i];
    }
    std::swap(kin, kout), std::swap(vin, vout);
  }
  if (kin != keys) std::copy_n(kin, n, keys), std::copy_n(vin, n, vals);
}

// Depth keys whose unsigned order is the order of positive depths.
inline uint32_t depth_key(float z) {
  uint32_t k;
  std::memcpy(&k, &z, 4);
  return k;
}
inline uint64_t depth_key(double z) {
  uint64_t k;
  std::memcpy(&k, &z, 8);
  return k;
}

template <class T>
TileBins bin_tiles_impl(const T* packed, const int32_t* rects, int64_t n, const CameraParams& cam) {
  using Key = decltype(depth_key(T(0)));
  const int64_t tiles_x = cam.tiles_x(), tiles = tiles_x * cam.tiles_y();
  const int64_t threads = std::max<int64_t>(1, at::get_num_threads());
  auto visible_in = [&](int64_t i) {
    const int32_t* r = rects + 4 * i;
    return r[0] < r[2] && r[1] < r[3];
  };
  // Four parallel regions (block counts, compaction, rectangle gather, fill), no more: on a busy machine each one
  // can wait for a descheduled thread.

  // 1. The visible Gaussians in id order, compacted in fixed blocks (count, prefix sum, fill), so the order never
  // depends on the thread count. The fill also counts each tile's intersections, per thread (integer sums, so
  // the totals are exact whichever thread counted what).
  const int64_t block = 8192, blocks = (n + block - 1) / block;
  std::vector<int64_t> block_start(size_t(blocks) + 1, 0);
  at::parallel_for(0, blocks, 1, [&](int64_t b0, int64_t b1) {
    for (int64_t b = b0; b < b1; ++b)
      for (int64_t i = b * block; i < std::min(n, (b + 1) * block); ++i) block_start[b + 1] += visible_in(i);
  });
  for (int64_t b = 0; b < blocks; ++b) block_start[b + 1] += block_start[b];
  const int64_t visible = block_start[blocks];
  auto keys = uninit<Key>(visible);
  auto order = uninit<int32_t>(visible);
  std::vector<int64_t> per_thread(size_t(threads * tiles), 0);
  at::parallel_for(0, blocks, 1, [&](int64_t b0, int64_t b1) {
    // A team never has more threads than get_num_threads(), and a nested or inline call runs as thread 0, so no
    // two threads share a row.
    const int64_t thread = at::get_thread_num();
    ISPLAT_CHECK(thread >= 0 && thread < threads, "bin_tiles: thread ", thread, " of ", threads);
    int64_t* h = per_thread.data() + thread * tiles;
    for (int64_t b = b0; b < b1; ++b) {
      int64_t k = block_start[b];
      for (int64_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
        if (!visible_in(i)) continue;
        keys[k] = depth_key(packed[i * kRec + kDepth]), order[k++] = int32_t(i);
        const int32_t* r = rects + 4 * i;
        for (int32_t ty = r[1]; ty < r[3]; ++ty)
          for (int32_t tx = r[0]; tx < r[2]; ++tx) ++h[ty * tiles_x + tx];
      }
    }
  });

  // 2. Sorted by (depth, id): the sort is stable and the ids ascend. Filling the tiles in this order leaves
  // every tile list sorted. The rectangles are copied into sorted order (the reads are random, so in
  // parallel), and the fill reads them sequentially.
  radix_sort(keys.get(), order.get(), visible);
  auto sorted_rects = uninit<int32_t>(4 * visible);
  at::parallel_for(0, visible, 4096, [&](int64_t k0, int64_t k1) {
    for (int64_t k = k0; k < k1; ++k) std::memcpy(&sorted_rects[4 * k], rects + 4 * int64_t(order[k]), 16);
  });

  // 3. Tile offsets from the counts.
  TileBins bins;
  bins.tile_offsets = torch::empty({tiles + 1}, torch::kInt64);
  int64_t* offs = bins.tile_offsets.data_ptr<int64_t>();
  int64_t total = 0;
  for (int64_t t = 0; t < tiles; ++t) {
    offs[t] = total;
    for (int64_t w = 0; w < threads; ++w) total += per_thread[w * tiles + t];
  }
  offs[tiles] = total;
  bins.isect_ids = torch::empty({total}, torch::kInt32);
  int32_t* ids = bins.isect_ids.data_ptr<int32_t>();

  // 4. The fill, in sorted order. Each worker owns a range of tiles holding about an equal share of the
  // intersections, scans the whole sorted list and writes only into its own tiles: no two workers share a
  // cursor, and each tile's list is written in sorted order by one worker.
  const int64_t workers = std::max<int64_t>(1, std::min<int64_t>(threads, tiles));
  std::vector<int64_t> cursor(offs, offs + tiles);
  at::parallel_for(0, workers, 1, [&](int64_t w0, int64_t w1) {
    for (int64_t w = w0; w < w1; ++w) {
      // Tiles [ta, tb): the first tile whose list starts at or after the worker's share of the total.
      auto first_tile_at = [&](int64_t share) {
        return int64_t(std::lower_bound(offs, offs + tiles, total * share / workers) - offs);
      };
      const int64_t ta = w == 0 ? 0 : first_tile_at(w), tb = w + 1 == workers ? tiles : first_tile_at(w + 1);
      if (ta >= tb) continue;
      const int64_t ya = ta / tiles_x, yb = (tb - 1) / tiles_x + 1;  // tile rows the range touches
      for (int64_t k = 0; k < visible; ++k) {
        const int32_t id = order[k];
        const int32_t* r = &sorted_rects[4 * k];
        const int64_t y_lo = std::max<int64_t>(r[1], ya), y_hi = std::min<int64_t>(r[3], yb);
        for (int64_t ty = y_lo; ty < y_hi; ++ty) {
          const int64_t lo = std::max(ty * tiles_x + r[0], ta), hi = std::min(ty * tiles_x + r[2], tb);
          for (int64_t t = lo; t < hi; ++t) ids[cursor[t]++] = id;
        }
      }
    }
  });
  return bins;
}

template <class T>
ISPLAT_INLINE Splat<T> fwd_splat(const T* rec) {
  return {rec[kU],    rec[kV],    rec[kConA], rec[kConB],
          rec[kConC], rec[kOpac], rec[kCut],  {rec[kR], rec[kG], rec[kB], rec[kDepth], rec[kNx], rec[kNy], rec[kNz]}};
}

// Row by row (each row's planes are one contiguous block), so the loops vectorize.
template <class T>
ISPLAT_INLINE void fwd_init(int64_t x0, int64_t y0, int64_t x1, int64_t y1, T* st, int32_t* last) {
  std::fill(st, st + kPix * kFwdPlanes, T(0));
  std::fill(last, last + kPix, 0);
  const int64_t w = x1 - x0, h = y1 - y0;
  for (int r = 0; r < kTile; ++r) {
    T* t = st + fwd_at(r * kTile, kPlT);
    for (int l = 0; l < kTile; ++l) t[l] = r < h && l < w ? T(1) : T(-1);  // outside: "stopped", never composited
  }
}

// Composites one tile's depth-sorted records front to back. Gaussian-major: each Gaussian visits only the
// 8-pixel groups of its box that it may hit; per pixel the order, skip rules and stop rule are those of the
// forward model. The AVX2 and AVX-512 loops below visit the same pixels; they find a Gaussian's groups for all 16 rows
// at once (tile_rows). kChannels: 7 composites colour, depth and normal, 4 leaves the normal out, 3 the depth too, 0
// composites nothing (a probe needs only T); kPlane: plane depth (depth_plane). kProbe max_weight: probe[i] receives
// the largest weight α·T entry i reaches in this tile (the contribution measure); entries never reached keep their
// value. kProbe median_depth: probe[p] (tile-local pixel, 0 beforehand) receives the depth of the first Gaussian after
// which the pixel's transmittance is 0.5 or less, and the pixel stops there (its sums are then not the forward's).
template <class T, int kChannels, bool kPlane, Probe kProbe = Probe::none>
void fwd_tile_generic(const T* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1, T* st,
                      int32_t* last, const CameraParams& cam, T* probe = nullptr) {
  fwd_init(x0, y0, x1, y1, st, last);
  Group<T> groups[kMaxGroups];
  LiveGroups live = unstopped_groups(st);
  int64_t active = (x1 - x0) * (y1 - y0), ys, ye, g0, g1;
  for (int64_t i = 0; i < count && active > 0; ++i) {
    const T* rec = local + i * kRec;
    if (!pixel_box(rec, x0, y0, x1, y1, ys, ye, g0, g1)) continue;
    Splat<T> s = fwd_splat(rec);
    const int n = collect_groups(s.prepare(), x0, y0, ys, ye, g0, g1, live, groups);
    const DepthPlane<T> plane = kPlane ? depth_plane(s, cam) : DepthPlane<T>{};
    int stops = 0;
    if constexpr (kProbe == Probe::max_weight) {
      T m = 0;
      auto keep_max = [&m](int, T w, T, T) { m = std::max(m, w); };
      for (int k = 0; k < n; ++k)
        stops += fwd_group<kChannels, kPlane>(s, plane, groups[k], st, last, int32_t(i + 1), keep_max);
      probe[i] = m;
    } else if constexpr (kProbe == Probe::median_depth) {
      auto first_half = [probe](int p, T, T next, T z) {  // found: the pixel needs no more Gaussians
        if (!(next <= T(0.5))) return false;
        probe[p] = z;
        return true;
      };
      for (int k = 0; k < n; ++k)
        stops += fwd_group<kChannels, kPlane>(s, plane, groups[k], st, last, int32_t(i + 1), first_half);
    } else {
      for (int k = 0; k < n; ++k) stops += fwd_group<kChannels, kPlane>(s, plane, groups[k], st, last, int32_t(i + 1));
    }
    if (stops > 0) active -= stops, live = unstopped_groups(st);
  }
}

#ifdef ISPLAT_HAVE_AVX2_LANES
// 16 lanes per register: whole tile rows for a Gaussian whose box spans both groups of a row, pairs of rows'
// groups for a narrower one (a last unpaired group with its high half masked off). Writes each entry's group hits.
// kProbe: one of fwd_tile_generic's probes instead (kChannels 0, group_hits null), into `probe` as it says.
template <int kChannels, bool kPlane, Probe kProbe = Probe::none>
ISPLAT_AVX512_FN void fwd_tile_avx512_impl(const float* local, int64_t count, int64_t x0, int64_t y0, int64_t x1,
                                           int64_t y1, float* st, int32_t* last, const CameraParams& cam,
                                           uint32_t* group_hits, float* probe) {
  fwd_init(x0, y0, x1, y1, st, last);
  if (group_hits) std::fill(group_hits, group_hits + count, 0u);  // entries skipped or never reached hit nothing
  JobList jobs;
  TileRows rows;
  PixelBoxes boxes;
  LiveGroups live = unstopped_groups_avx512(st);
  int64_t ys, ye, g0, g1;
  for (int64_t i = 0; i < count && (live.half[0] | live.half[1]) != 0; ++i) {  // until every pixel has stopped
    const float* rec = local + i * kRec;
    if (i % 16 == 0) pixel_boxes(rec, count - i, x0, y0, x1, y1, boxes);  // the next 16 entries' boxes
    if (!boxes.unpack(int(i % 16), y0, ys, ye, g0, g1)) continue;
    Splat<float> s = fwd_splat(rec);
    s.prepare();
    tile_rows(s, x0, y0, ys, ye, g0, g1, live, rows);
    if ((rows.groups[0] | rows.groups[1]) == 0) continue;
    const int32_t id = int32_t(i + 1);
    // The median probe reads the depth, f[3].
    const Avx512Splat a = avx512_splat(s, kProbe == Probe::median_depth ? 4 : kChannels);
    const Avx512Plane plane = kPlane ? avx512_plane(depth_plane(s, cam)) : Avx512Plane{};
    unsigned stops;  // nonzero if a pixel stopped
    uint32_t hits = 0;
    ProbeOut out{_mm512_setzero_ps(), probe};
    if (g1 - g0 == 2) {
      const int n = row_jobs(rows, jobs);
      stops = fwd_all_jobs_avx512<kChannels, kPlane, true, kProbe>(a, plane, {rows, 0, int32_t(x0)}, jobs, n, st, last,
                                                                   id, hits, out);
    } else {
      const int n = pair_jobs(rows, int(g0), jobs);
      const int32_t col = int32_t(g0) * kLanes;
      stops = fwd_all_jobs_avx512<kChannels, kPlane, false, kProbe>(a, plane, {rows, col, int32_t(x0) + col}, jobs, n,
                                                                    st, last, id, hits, out);
    }
    // An entry with no group to visit keeps its value, 0: the portable loop's m stays 0 there.
    if constexpr (kProbe == Probe::max_weight) probe[i] = _mm512_reduce_max_ps(out.max_weight);
    if (group_hits) group_hits[i] = hits;
    if (stops != 0) live = unstopped_groups_avx512(st);
  }
}
template <int kChannels, bool kPlane>
ISPLAT_AVX512_FN void fwd_tile_avx512(const float* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                                      float* st, int32_t* last, const CameraParams& cam, uint32_t* group_hits) {
  fwd_tile_avx512_impl<kChannels, kPlane>(local, count, x0, y0, x1, y1, st, last, cam, group_hits, nullptr);
}

template <int kChannels, bool kPlane>
ISPLAT_AVX2_FN void fwd_tile_avx2(const float* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                                  float* st, int32_t* last, const CameraParams& cam, uint32_t* group_hits) {
  fwd_init(x0, y0, x1, y1, st, last);
  if (group_hits) std::fill(group_hits, group_hits + count, 0u);
  Group<float> groups[kMaxGroups];
  TileRows rows;
  LiveGroups live = avx2_unstopped_groups(st);
  int64_t ys, ye, g0, g1;
  for (int64_t i = 0; i < count && (live.half[0] | live.half[1]) != 0; ++i) {  // until every pixel has stopped
    const float* rec = local + i * kRec;
    if (!pixel_box(rec, x0, y0, x1, y1, ys, ye, g0, g1)) continue;
    Splat<float> s = fwd_splat(rec);
    avx2_tile_rows(s.prepare(), x0, y0, ys, ye, g0, g1, live, rows);
    if ((rows.groups[0] | rows.groups[1]) == 0) continue;
    const int n = avx2_groups(rows, x0, groups);
    const Avx2Splat a = avx2_splat(s, kChannels);  // broadcasts only the channels composited
    const Avx2Plane plane = kPlane ? avx2_plane(depth_plane(s, cam)) : Avx2Plane{};
    const int32_t id = int32_t(i + 1);
    int k = 0, stops = 0;
    uint32_t hits = 0;
    for (; k + 4 <= n; k += 4) stops += fwd_groups_avx2<4, kChannels, kPlane>(a, plane, groups + k, st, last, id, hits);
    for (; k + 2 <= n; k += 2) stops += fwd_groups_avx2<2, kChannels, kPlane>(a, plane, groups + k, st, last, id, hits);
    if (k < n) stops += fwd_groups_avx2<1, kChannels, kPlane>(a, plane, groups + k, st, last, id, hits);
    if (group_hits) group_hits[i] = hits;
    if (stops > 0) live = avx2_unstopped_groups(st);
  }
}
#endif

// The last argument receives the entries' group hits, or is nullptr (the vector loops then record none; the portable
// loops always ignore it).
template <class T>
using FwdTileFn = void (*)(const T*, int64_t, int64_t, int64_t, int64_t, int64_t, T*, int32_t*, const CameraParams&,
                           uint32_t*);

template <class T, int kChannels, bool kPlane>
void fwd_tile_portable(const T* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1, T* st,
                       int32_t* last, const CameraParams& cam, uint32_t*) {
  fwd_tile_generic<T, kChannels, kPlane>(local, count, x0, y0, x1, y1, st, last, cam);
}

// The tile loop for these channels at the SIMD level in use (float), else portable.
template <class T>
FwdTileFn<T> fwd_tile_fn(const RasterChannels& ch) {
  const bool rgb_only = !ch.normals && !ch.depth;  // plane depth then changes nothing
#ifdef ISPLAT_HAVE_AVX2_LANES
  if constexpr (std::is_same_v<T, float>) {
    if (simd_level() == Simd::avx512)
      return rgb_only     ? fwd_tile_avx512<3, false>
             : ch.normals ? (ch.plane_depth ? fwd_tile_avx512<7, true> : fwd_tile_avx512<7, false>)
                          : (ch.plane_depth ? fwd_tile_avx512<4, true> : fwd_tile_avx512<4, false>);
    if (simd_level() == Simd::avx2)
      return rgb_only     ? fwd_tile_avx2<3, false>
             : ch.normals ? (ch.plane_depth ? fwd_tile_avx2<7, true> : fwd_tile_avx2<7, false>)
                          : (ch.plane_depth ? fwd_tile_avx2<4, true> : fwd_tile_avx2<4, false>);
  }
#endif
  return rgb_only     ? fwd_tile_portable<T, 3, false>
         : ch.normals ? (ch.plane_depth ? fwd_tile_portable<T, 7, true> : fwd_tile_portable<T, 7, false>)
                      : (ch.plane_depth ? fwd_tile_portable<T, 4, true> : fwd_tile_portable<T, 4, false>);
}

// normal_out (depth_out) == nullptr when the channels leave the normal (depth) out: it is then neither composited nor
// written.
template <class T>
void rasterize_fwd_impl(const T* packed, const int64_t* offs, const int32_t* ids, const CameraParams& cam,
                        const RasterChannels& channels, const double* background, T* rgb, T* alpha_out, T* depth_out,
                        T* normal_out, T* final_T, int32_t* n_contrib, uint32_t* group_hits) {
  const int64_t W = cam.width, HW = W * cam.height;
  const T bg[3] = {T(background[0]), T(background[1]), T(background[2])};
  const FwdTileFn<T> tile_fn = fwd_tile_fn<T>(channels);
  for_each_tile<T>(cam, [&](int64_t tile, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch) {
    T* st = scratch.pixel_planes(kFwdPlanes);
    const int64_t begin = offs[tile], count = offs[tile + 1] - begin;
    tile_fn(scratch.gather(packed, ids + begin, count), count, x0, y0, x1, y1, st, scratch.last.data(), cam,
            group_hits ? group_hits + begin : nullptr);
    // Row by row, plane by plane: each inner loop runs over contiguous values, so it vectorizes.
    const int64_t w = x1 - x0;
    for (int64_t py = y0; py < y1; ++py) {
      const int r = int(py - y0);
      const T* plane = st + fwd_at(r * kTile, 0);  // plane k of this row: plane[k * kTile + lane]
      const int64_t o = py * W + x0;
      for (int64_t l = 0; l < w; ++l) final_T[o + l] = std::abs(plane[kPlT * kTile + l]);  // stopped pixels hold −T
      for (int64_t l = 0; l < w; ++l) alpha_out[o + l] = 1 - final_T[o + l];
      for (int c = 0; c < 3; ++c)
        for (int64_t l = 0; l < w; ++l) rgb[c * HW + o + l] = plane[(kPlAcc + c) * kTile + l] + final_T[o + l] * bg[c];
      if (depth_out) copy_row(plane + (kPlAcc + 3) * kTile, w, depth_out + o);
      if (normal_out)
        for (int c = 0; c < 3; ++c) copy_row(plane + (kPlAcc + 4 + c) * kTile, w, normal_out + c * HW + o);
      copy_row(scratch.last.data() + r * kTile, w, n_contrib + o);
    }
  });
}

// One tile of a probe of fwd_tile_generic (kProbe, into `probe` as it says): the AVX-512 loops where the CPU has them
// (float), else the portable ones, which give the same values bit for bit.
template <class T, bool kPlane, Probe kProbe>
void probe_tile(const T* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch,
                const CameraParams& cam, T* probe) {
  T* st = scratch.pixel_planes(kFwdPlanes);
#ifdef ISPLAT_HAVE_AVX2_LANES
  if constexpr (std::is_same_v<T, float>) {
    if (simd_level() == Simd::avx512) {
      fwd_tile_avx512_impl<0, kPlane, kProbe>(local, count, x0, y0, x1, y1, st, scratch.last.data(), cam, nullptr,
                                              probe);
      return;
    }
  }
#endif
  fwd_tile_generic<T, 0, kPlane, kProbe>(local, count, x0, y0, x1, y1, st, scratch.last.data(), cam, probe);
}

// The largest weight w = α·T each tile-list entry reaches in its tile, written at the entry's position in the
// intersection list (so no two threads ever write the same place). Same rule as fwd_tile_generic.
template <class T>
void max_weight_impl(const T* packed, const int64_t* offs, const int32_t* ids, const CameraParams& cam, T* per_entry) {
  for_each_tile<T>(cam, [&](int64_t tile, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch) {
    const int64_t begin = offs[tile], count = offs[tile + 1] - begin;
    probe_tile<T, false, Probe::max_weight>(scratch.gather(packed, ids + begin, count), count, x0, y0, x1, y1, scratch,
                                            cam, per_entry + begin);
  });
}

// Each pixel's median depth (rasterize_median_depth), tile by tile with the forward's rules.
template <class T, bool kPlane>
void median_depth_impl(const T* packed, const int64_t* offs, const int32_t* ids, const CameraParams& cam, T* out) {
  const int64_t W = cam.width;
  for_each_tile<T>(cam, [&](int64_t tile, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch) {
    const int64_t begin = offs[tile], count = offs[tile + 1] - begin;
    alignas(64) T median[kPix] = {};
    probe_tile<T, kPlane, Probe::median_depth>(scratch.gather(packed, ids + begin, count), count, x0, y0, x1, y1,
                                               scratch, cam, median);
    for (int64_t py = y0; py < y1; ++py) std::copy_n(median + (py - y0) * kTile, x1 - x0, out + py * W + x0);
  });
}

}  // namespace

namespace {
Simd cpu_simd() {
#ifdef ISPLAT_HAVE_AVX2_LANES
  __builtin_cpu_init();  // may run before main (static initialization)
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return Simd::portable;
  const bool avx512 =
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
  return avx512 ? Simd::avx512 : Simd::avx2;
#else
  return Simd::portable;
#endif
}
std::atomic<Simd> g_simd{cpu_simd()};
}  // namespace
const char* simd_name(Simd level) {
  return level == Simd::avx512 ? "avx512" : level == Simd::avx2 ? "avx2" : "portable";
}
Simd simd_supported() {
  static const Simd best = cpu_simd();
  return best;
}
Simd simd_level() {
  return g_simd.load();
}
Simd set_simd_level(Simd level) {
  return g_simd.exchange(std::min(level, simd_supported()));
}

TileBins bin_tiles(const Projection& proj, const CameraParams& cam) {
  TileBins bins;
  AT_DISPATCH_FLOATING_TYPES(proj.packed.scalar_type(), "bin_tiles", [&] {
    bins = bin_tiles_impl<scalar_t>(proj.packed.data_ptr<scalar_t>(), proj.rects.data_ptr<int32_t>(),
                                    proj.packed.size(0), cam);
  });
  return bins;
}

RasterOutput rasterize_fwd(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                           const double background[3], const RasterChannels& channels) {
  const int64_t H = cam.height, W = cam.width;
  const auto opts = packed.options();
  const bool depth = channels.normals || channels.depth;
  RasterOutput out{torch::empty({3, H, W}, opts),
                   torch::empty({1, H, W}, opts),
                   depth ? torch::empty({1, H, W}, opts) : torch::empty({0}, opts),
                   channels.normals ? torch::empty({3, H, W}, opts) : torch::empty({0}, opts),
                   torch::empty({H, W}, opts),
                   torch::empty({H, W}, opts.dtype(torch::kInt32)),
                   torch::Tensor()};
  const bool hits = channels.group_hits && packed.scalar_type() == torch::kFloat32 && simd_level() != Simd::portable;
  out.group_hits = torch::empty({hits ? bins.intersections() : 0}, opts.dtype(torch::kInt32));
  uint32_t* group_hits = hits ? reinterpret_cast<uint32_t*>(out.group_hits.data_ptr<int32_t>()) : nullptr;
  AT_DISPATCH_FLOATING_TYPES(packed.scalar_type(), "rasterize_fwd", [&] {
    rasterize_fwd_impl<scalar_t>(
        packed.data_ptr<scalar_t>(), bins.tile_offsets.data_ptr<int64_t>(), bins.isect_ids.data_ptr<int32_t>(), cam,
        channels, background, out.rgb.data_ptr<scalar_t>(), out.alpha.data_ptr<scalar_t>(),
        depth ? out.depth.data_ptr<scalar_t>() : nullptr, channels.normals ? out.normal.data_ptr<scalar_t>() : nullptr,
        out.final_T.data_ptr<scalar_t>(), out.n_contrib.data_ptr<int32_t>(), group_hits);
  });
  return out;
}

torch::Tensor rasterize_median_depth(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                                     bool plane_depth) {
  torch::Tensor out = torch::empty({1, cam.height, cam.width}, packed.options());
  AT_DISPATCH_FLOATING_TYPES(packed.scalar_type(), "rasterize_median_depth", [&] {
    (plane_depth
         ? median_depth_impl<scalar_t, true>
         : median_depth_impl<scalar_t, false>)(packed.data_ptr<scalar_t>(), bins.tile_offsets.data_ptr<int64_t>(),
                                               bins.isect_ids.data_ptr<int32_t>(), cam, out.data_ptr<scalar_t>());
  });
  return out;
}

torch::Tensor rasterize_max_weight(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam) {
  const int64_t n = packed.size(0), entries = bins.intersections();
  torch::Tensor per_entry = torch::zeros({entries}, packed.options());
  torch::Tensor out = torch::zeros({n}, packed.options());
  AT_DISPATCH_FLOATING_TYPES(packed.scalar_type(), "rasterize_max_weight", [&] {
    max_weight_impl<scalar_t>(packed.data_ptr<scalar_t>(), bins.tile_offsets.data_ptr<int64_t>(),
                              bins.isect_ids.data_ptr<int32_t>(), cam, per_entry.data_ptr<scalar_t>());
    const scalar_t* m = per_entry.data_ptr<scalar_t>();
    const int32_t* ids = bins.isect_ids.data_ptr<int32_t>();
    scalar_t* o = out.data_ptr<scalar_t>();
    for (int64_t k = 0; k < entries; ++k) o[ids[k]] = std::max(o[ids[k]], m[k]);
  });
  return out;
}

}  // namespace isplat::splat

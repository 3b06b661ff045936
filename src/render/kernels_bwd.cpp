// Backward rasterization: per tile, back to front from each pixel's last contributor, then a deterministic
// reduction of the per-intersection gradients to per-Gaussian 2D gradients.
#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>

#include <vector>

#include "render/kernels.h"
#include "render/lanes_avx512.h"
#include "render/tile_loop.h"

namespace isplat::splat {
namespace {

template <class T>
ISPLAT_INLINE Splat<T> bwd_splat(const T* rec) {
  return {rec[kU],    rec[kV],    rec[kConA], rec[kConB],
          rec[kConC], rec[kOpac], rec[kCut],  {rec[kR], rec[kG], rec[kB], rec[kDepth], T(1)}};
}

// One tile back to front. Each pixel starts at its last contributor with T = T_final and reconstructs the
// transmittance in front of every Gaussian by division; the skip rules are evaluated exactly as in forward.
// Writes the tile's per-intersection gradients (kGrad2d each) to `out`. The AVX2 twin has the same loops. kCh: the
// gradient planes read (bwd_group).
template <class T, int kCh>
void bwd_tile_generic(const T* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1, T* st,
                      const int32_t* last, int32_t max_last, T* out, const uint32_t*) {
  std::fill(out + int64_t(max_last) * kGrad2d, out + count * kGrad2d, T(0));
  Group<T> groups[kMaxGroups];
  const GroupLast group_last(last);
  for (int64_t i = max_last - 1; i >= 0; --i) {
    const T* rec = local + i * kRec;
    LaneSums<T> sums{};
    int64_t ys, ye, g0, g1;
    Splat<T> s = bwd_splat(rec);
    if (pixel_box(rec, x0, y0, x1, y1, ys, ye, g0, g1)) {
      const int n = collect_groups(s.prepare(), x0, y0, ys, ye, g0, g1, group_last.live_for(int32_t(i)), groups);
      for (int k = 0; k < n; ++k) bwd_group<kCh>(s, groups[k], st, last, int32_t(i), sums);
    }
    sums.reduce(out + i * kGrad2d);
    moments_to_grads(s, out + i * kGrad2d);
  }
}

#ifdef ISPLAT_HAVE_AVX2_LANES
// With the forward's group hits (non-null), each entry visits exactly the groups where it composited a pixel, in
// the row-major order collect_groups gives (see bwd_tile_avx512).
template <int kCh>
ISPLAT_AVX2_FN void bwd_tile_avx2(const float* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                                  float* st, const int32_t* last, int32_t max_last, float* out,
                                  const uint32_t* group_hits) {
  std::fill(out + int64_t(max_last) * kGrad2d, out + count * kGrad2d, 0.0f);
  Group<float> groups[kMaxGroups];
  const GroupLast group_last(last);
  for (int64_t i = max_last - 1; i >= 0; --i) {
    const float* rec = local + i * kRec;
    float* slot = out + i * kGrad2d;
    int64_t ys, ye, g0, g1;
    Splat<float> s = bwd_splat(rec);
    int n = 0;
    if (group_hits) {
      const uint32_t m = group_hits[i];
      if (m != 0) {
        s.prepare();
        for (int r = 0; r < kTile; ++r) {
          if (((m >> r) | (m >> (16 + r))) & 1u) {
            const Row<float> row = make_row(s, y0 + r);
            for (int h = 0; h < 2; ++h) {
              groups[n] = {row, int32_t(x0) + h * kLanes, r * kTile + h * kLanes};
              n += int((m >> (16 * h + r)) & 1u);
            }
          }
        }
      }
    } else if (pixel_box(rec, x0, y0, x1, y1, ys, ye, g0, g1)) {
      n = collect_groups(s.prepare(), x0, y0, ys, ye, g0, g1, group_last.live_for(int32_t(i)), groups);
    }
    if (n == 0) {
      std::fill(slot, slot + kGrad2d, 0.0f);
      continue;
    }
    const Avx2Splat a = avx2_splat(s, kCh);
    Avx2Sums g[2];
    g[0].zero(), g[1].zero();
    int k = 0;
    for (; k + 4 <= n; k += 4) bwd_groups_avx2<4, kCh>(a, groups + k, st, last, int32_t(i), g);
    for (; k + 2 <= n; k += 2) bwd_groups_avx2<2, kCh>(a, groups + k, st, last, int32_t(i), g);
    if (k < n) bwd_groups_avx2<1, kCh>(a, groups + k, st, last, int32_t(i), g);
    reduce_sets(g, slot);
    moments_to_grads(s, slot);
  }
}

// 16 lanes per register: whole tile rows for a Gaussian that hits both groups of a row, pairs of rows' groups for
// one that hits a single column (a last unpaired group with its high half masked off).
// With the forward's group hits (non-null), each entry visits exactly the groups where it composited a pixel: the
// lanes that contribute here are the lanes it composited there, so no box or culling test is needed, and an entry
// that composited nothing costs a load. Without them, the groups come from the box, the culling and the live set.
// Either way, only groups without a contributing lane differ, and those add exact zeros.
template <int kCh>
ISPLAT_AVX512_FN void bwd_tile_avx512(const float* local, int64_t count, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                                      float* st, const int32_t* last, int32_t max_last, float* out,
                                      const uint32_t* group_hits) {
  std::fill(out + int64_t(max_last) * kGrad2d, out + count * kGrad2d, 0.0f);
  JobList jobs;
  TileRows rows;
  const GroupLast group_last(last);
  for (int64_t i = max_last - 1; i >= 0; --i) {
    const float* rec = local + i * kRec;
    float* slot = out + i * kGrad2d;
    int64_t ys, ye, g0, g1;
    Splat<float> s = bwd_splat(rec);
    if (group_hits) {
      rows.groups[0] = group_hits[i] & 0xffffu, rows.groups[1] = group_hits[i] >> 16;
      if ((rows.groups[0] | rows.groups[1]) != 0) row_terms(s.prepare(), y0, rows);
      g0 = rows.groups[0] != 0 ? 0 : 1, g1 = rows.groups[1] != 0 ? 2 : 1;
    } else if (pixel_box(rec, x0, y0, x1, y1, ys, ye, g0, g1)) {
      tile_rows(s.prepare(), x0, y0, ys, ye, g0, g1, live_for_avx512(group_last, int32_t(i)), rows);
    } else {
      rows.groups[0] = rows.groups[1] = 0;
    }
    if ((rows.groups[0] | rows.groups[1]) == 0) {
      std::fill(slot, slot + kGrad2d, 0.0f);
      continue;
    }
    const Avx512Splat a = avx512_splat(s, kCh);
    if (g1 - g0 == 2) {
      Avx512Sums g;
      g.zero();
      bwd_all_jobs_avx512<true, kCh>(a, {rows, 0, int32_t(x0)}, jobs, row_jobs(rows, jobs), st, last, int32_t(i), {g});
      g.reduce(slot);
      moments_to_grads(s, slot);
      continue;
    }
    const int n = pair_jobs(rows, int(g0), jobs);
    Avx2Sums g[2];  // all in the set of column g0
    g[0].zero(), g[1].zero();
    const int32_t col = int32_t(g0) * kLanes;
    bwd_all_jobs_avx512<false, kCh>(a, {rows, col, int32_t(x0) + col}, jobs, n, st, last, int32_t(i), {g[g0]});
    reduce_sets(g, slot);
    moments_to_grads(s, slot);
  }
}
#endif

// g_alpha and g_depth are null when only colour has a gradient: the pixel loops then read kBwdRgb planes.
template <class T>
void rasterize_bwd_impl(const T* packed, const int64_t* offs, const int32_t* ids, const CameraParams& cam,
                        const double* background, const T* final_T, const int32_t* n_contrib, const T* g_rgb,
                        const T* g_alpha, const T* g_depth, const uint32_t* group_hits, T* slots) {
  const int64_t W = cam.width, HW = W * cam.height;
  const bool rgb_only = g_alpha == nullptr;
  const int channels = rgb_only ? kBwdRgb : kBwdCh;
  auto tile_fn = rgb_only ? bwd_tile_generic<T, kBwdRgb> : bwd_tile_generic<T, kBwdCh>;
#ifdef ISPLAT_HAVE_AVX2_LANES
  if constexpr (std::is_same_v<T, float>) {
    if (simd_level() == Simd::avx512) tile_fn = rgb_only ? bwd_tile_avx512<kBwdRgb> : bwd_tile_avx512<kBwdCh>;
    if (simd_level() == Simd::avx2) tile_fn = rgb_only ? bwd_tile_avx2<kBwdRgb> : bwd_tile_avx2<kBwdCh>;
  }
#endif
  for_each_tile<T>(cam, [&](int64_t tile, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch) {
    const int64_t begin = offs[tile], count = offs[tile + 1] - begin;
    if (count == 0) return;
    T* st = scratch.pixel_planes(kBwdPlanes);
    int32_t* last = scratch.last.data();
    std::fill(st, st + kBwdPlanes * kPix, T(0));
    std::fill(last, last + kPix, 0);
    // Pixels outside the image keep last = 0 (never a contributor) and T = 1 (their masked lanes divide by it).
    for (int p = 0; p < kPix; ++p) st[bwd_at(p, kPbT)] = 1;
    // Row by row, plane by plane: each inner loop runs over contiguous values, so it vectorizes.
    const int64_t w = x1 - x0;
    const T bg[3] = {T(background[0]), T(background[1]), T(background[2])};
    int32_t max_last = 0;
    for (int64_t py = y0; py < y1; ++py) {
      const int r = int(py - y0);
      T* plane = st + bwd_at(r * kTile, 0);  // plane k of this row: plane[k * kTile + lane]
      const int64_t o = py * W + x0;
      const T* dc[kBwdCh] = {g_rgb + o, g_rgb + HW + o, g_rgb + 2 * HW + o, rgb_only ? nullptr : g_depth + o,
                             rgb_only ? nullptr : g_alpha + o};
      copy_row(final_T + o, w, plane + kPbT * kTile);
      for (int c = 0; c < channels; ++c) copy_row(dc[c], w, plane + (kPbDC + c) * kTile);
      // Behind the last contributor lies the background (zero for depth and alpha).
      for (int64_t l = 0; l < w; ++l) plane[kPbS * kTile + l] = dc[0][l] * bg[0] + dc[1][l] * bg[1] + dc[2][l] * bg[2];
      copy_row(n_contrib + o, w, last + r * kTile);
      for (int64_t l = 0; l < w; ++l) max_last = std::max(max_last, last[r * kTile + l]);
    }
    tile_fn(scratch.gather(packed, ids + begin, max_last), count, x0, y0, x1, y1, st, last, max_last,
            slots + begin * kGrad2d, group_hits ? group_hits + begin : nullptr);
  });
}

// grad2d[id] = Σ of its intersection slots in tile order. Each worker owns a range of ids and scans all
// intersections, so every sum has the same order whatever the thread count: bit-identical results.
template <class T>
void reduce_slots(const int32_t* ids, int64_t intersections, const T* slots, int64_t n, T* grad2d) {
  std::fill(grad2d, grad2d + n * kGrad2d, T(0));
  const int64_t workers = std::max<int64_t>(1, std::min<int64_t>(at::get_num_threads(), n));
  at::parallel_for(0, workers, 1, [&](int64_t w0, int64_t w1) {
    for (int64_t w = w0; w < w1; ++w) {
      const int64_t lo = n * w / workers, hi = n * (w + 1) / workers;
      for (int64_t k = 0; k < intersections; ++k) {
        const int64_t id = ids[k];
        if (id < lo || id >= hi) continue;
        const T* s = slots + k * kGrad2d;
        T* g = grad2d + id * kGrad2d;
        for (int c = 0; c < kGrad2d; ++c) g[c] += s[c];
      }
    }
  });
}

}  // namespace

torch::Tensor rasterize_bwd(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                            const double background[3], const torch::Tensor& final_T, const torch::Tensor& n_contrib,
                            const torch::Tensor& grad_rgb, const torch::Tensor& grad_alpha,
                            const torch::Tensor& grad_depth, const torch::Tensor& group_hits) {
  const int64_t H = cam.height, W = cam.width, n = packed.size(0), isects = bins.intersections();
  // The forward's group hits, where it left them for these bins (AVX2 or AVX-512, float); the portable loops ignore
  // them.
  const uint32_t* hits = group_hits.defined() && group_hits.numel() == isects && isects > 0
                             ? reinterpret_cast<const uint32_t*>(group_hits.data_ptr<int32_t>())
                             : nullptr;
  const auto opts = packed.options();
  auto prepare = [&](const torch::Tensor& g, int64_t channels) {
    return g.defined() ? g.to(opts).contiguous() : torch::zeros({channels, H, W}, opts);
  };
  // Only colour has a gradient (a colour loss): the depth and alpha planes are left out rather than read as zeros.
  const bool rgb_only = !grad_alpha.defined() && !grad_depth.defined();
  const auto g_rgb = prepare(grad_rgb, 3);
  const auto g_alpha = rgb_only ? torch::Tensor() : prepare(grad_alpha, 1);
  const auto g_depth = rgb_only ? torch::Tensor() : prepare(grad_depth, 1);
  auto slots = torch::empty({isects, kGrad2d}, opts);
  auto grad2d = torch::empty({n, kGrad2d}, opts);
  AT_DISPATCH_FLOATING_TYPES(packed.scalar_type(), "rasterize_bwd", [&] {
    rasterize_bwd_impl<scalar_t>(packed.data_ptr<scalar_t>(), bins.tile_offsets.data_ptr<int64_t>(),
                                 bins.isect_ids.data_ptr<int32_t>(), cam, background, final_T.data_ptr<scalar_t>(),
                                 n_contrib.data_ptr<int32_t>(), g_rgb.data_ptr<scalar_t>(),
                                 rgb_only ? nullptr : g_alpha.data_ptr<scalar_t>(),
                                 rgb_only ? nullptr : g_depth.data_ptr<scalar_t>(), hits, slots.data_ptr<scalar_t>());
    reduce_slots<scalar_t>(bins.isect_ids.data_ptr<int32_t>(), isects, slots.data_ptr<scalar_t>(), n,
                           grad2d.data_ptr<scalar_t>());
  });
  return grad2d;
}

}  // namespace isplat::splat

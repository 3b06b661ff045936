// Backward rasterization: per tile, back to front from each pixel's last contributor, then a deterministic
// reduction of the per-intersection gradients to per-Gaussian 2D gradients.
#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>

#include <vector>

#include "render/kernels.h"
#include "render/tile_loop.h"

namespace isplat::splat {
namespace {

// Channels composited per pixel in backward: r, g, b, depth, and "one" (alpha = Σ wᵢ·1).
constexpr int kCh = 5;
// Pixel state: T, dL/dC[5], B[5] (what lies behind the current Gaussian, background included).
constexpr int kStride = 1 + 2 * kCh;

template <class T>
void rasterize_bwd_impl(const T* packed, const int64_t* offs, const int32_t* ids, const CameraParams& cam,
                        const double* background, const T* final_T, const int32_t* n_contrib, const T* g_rgb,
                        const T* g_alpha, const T* g_depth, T* slots) {
  const int64_t W = cam.width, HW = W * cam.height;
  for_each_tile<T>(cam, [&](int64_t tile, int64_t x0, int64_t y0, int64_t x1, int64_t y1, TileScratch<T>& scratch) {
    const int64_t begin = offs[tile], count = offs[tile + 1] - begin;
    if (count == 0) return;
    T* st = scratch.pixel_state(kStride);
    int32_t* last = scratch.last;
    int32_t max_last = 0;
    for (int64_t p = 0; p < kTile * kTile; ++p) last[p] = 0;
    for (int64_t py = y0; py < y1; ++py)
      for (int64_t px = x0; px < x1; ++px) {
        const int64_t p = (py - y0) * kTile + (px - x0), o = py * W + px;
        T* s = st + kStride * p;
        s[0] = final_T[o];
        s[1] = g_rgb[o], s[2] = g_rgb[HW + o], s[3] = g_rgb[2 * HW + o], s[4] = g_depth[o], s[5] = g_alpha[o];
        s[6] = T(background[0]), s[7] = T(background[1]), s[8] = T(background[2]), s[9] = 0, s[10] = 0;
        last[p] = n_contrib[o];
        max_last = std::max(max_last, last[p]);
      }
    const T* local = scratch.gather(packed, ids + begin, max_last);
    T* out = slots + begin * kGrad2d;
    std::fill(out + int64_t(max_last) * kGrad2d, out + count * kGrad2d, T(0));
    for (int64_t i = max_last - 1; i >= 0; --i) {
      const T* rec = local + i * kRec;
      const T f[kCh] = {rec[kR], rec[kG], rec[kB], rec[kDepth], T(1)};
      T g[kGrad2d] = {0};
      const Ellipse e(rec);
      int64_t ys, ye;
      if (e.rows(y0, y1, ys, ye))
        for (int64_t py = ys; py < ye; ++py) {
          int64_t xs, xe;
          if (!e.span(py, x0, x1, xs, xe)) continue;
          const T dy = T(py) + T(0.5) - rec[kV];
          for (int64_t px = xs; px < xe; ++px) {
            const int64_t p = (py - y0) * kTile + (px - x0);
            if (i >= last[p]) continue;  // behind this pixel's stop
            const T dx = T(px) + T(0.5) - rec[kU];
            T alpha, G, raw;
            if (!splat_alpha(rec, dx, dy, alpha, G, raw)) continue;  // the forward skipped it too
            T* s = st + kStride * p;
            const T Ti = s[0] / (1 - alpha);  // transmittance in front of Gaussian i
            s[0] = Ti;
            const T w = alpha * Ti;
            T d_alpha = 0;
            for (int c = 0; c < kCh; ++c) d_alpha += s[1 + c] * (f[c] - s[6 + c]);
            d_alpha *= Ti;
            g[6] += w * s[1], g[7] += w * s[2], g[8] += w * s[3], g[9] += w * s[4];
            for (int c = 0; c < kCh; ++c) s[6 + c] = alpha * f[c] + (1 - alpha) * s[6 + c];
            if (raw > T(kAlphaMax)) continue;  // clamped: α does not depend on the parameters
            g[5] += G * d_alpha;
            const T d_power = -alpha * d_alpha;
            g[0] -= d_power * (rec[kConA] * dx + rec[kConB] * dy);
            g[1] -= d_power * (rec[kConB] * dx + rec[kConC] * dy);
            g[2] += d_power * T(0.5) * dx * dx;
            g[3] += d_power * dx * dy;
            g[4] += d_power * T(0.5) * dy * dy;
          }
        }
      std::copy(g, g + kGrad2d, out + i * kGrad2d);
    }
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
                            const torch::Tensor& grad_depth) {
  const int64_t H = cam.height, W = cam.width, n = packed.size(0), isects = bins.intersections();
  const auto opts = packed.options();
  auto prepare = [&](const torch::Tensor& g, int64_t channels) {
    return g.defined() ? g.to(opts).contiguous() : torch::zeros({channels, H, W}, opts);
  };
  const auto g_rgb = prepare(grad_rgb, 3), g_alpha = prepare(grad_alpha, 1), g_depth = prepare(grad_depth, 1);
  auto slots = torch::empty({isects, kGrad2d}, opts);
  auto grad2d = torch::empty({n, kGrad2d}, opts);
  AT_DISPATCH_FLOATING_TYPES(packed.scalar_type(), "rasterize_bwd", [&] {
    rasterize_bwd_impl<scalar_t>(
        packed.data_ptr<scalar_t>(), bins.tile_offsets.data_ptr<int64_t>(), bins.isect_ids.data_ptr<int32_t>(), cam,
        background, final_T.data_ptr<scalar_t>(), n_contrib.data_ptr<int32_t>(), g_rgb.data_ptr<scalar_t>(),
        g_alpha.data_ptr<scalar_t>(), g_depth.data_ptr<scalar_t>(), slots.data_ptr<scalar_t>());
    reduce_slots<scalar_t>(bins.isect_ids.data_ptr<int32_t>(), isects, slots.data_ptr<scalar_t>(), n,
                           grad2d.data_ptr<scalar_t>());
  });
  return grad2d;
}

}  // namespace isplat::splat

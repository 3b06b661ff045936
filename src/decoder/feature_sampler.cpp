// Forward: gather 4 texels per point from a channel-last copy. Backward: points bucketed per texel
// (counting sort), then each texel sums its contributions in point order: parallel and deterministic.
#include "decoder/feature_sampler.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/fast_exp.h"

namespace isplat {
namespace {

// Four texel indices and weights for one point, exactly as grid_sample computes them.
template <class T>
void corners(T u, T v, int64_t width, int64_t height, int64_t h, int64_t w, int64_t (&idx)[4], T (&wt)[4]) {
  const T lim = T(1) - T(1e-6);
  const T xn = std::clamp(u * (T(2) / width) - T(1), -lim, lim), yn = std::clamp(v * (T(2) / height) - T(1), -lim, lim);
  // align_corners = false: source coordinate = ((x + 1) * size - 1) / 2, then border padding clamps it.
  const T x = std::clamp(((xn + 1) * w - 1) / 2, T(0), T(w - 1)),
          y = std::clamp(((yn + 1) * h - 1) / 2, T(0), T(h - 1));
  const int64_t x0 = static_cast<int64_t>(std::floor(x)), y0 = static_cast<int64_t>(std::floor(y));
  const int64_t x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const T fx = x - x0, fy = y - y0;
  idx[0] = y0 * w + x0, idx[1] = y0 * w + x1, idx[2] = y1 * w + x0, idx[3] = y1 * w + x1;
  wt[0] = (1 - fx) * (1 - fy), wt[1] = fx * (1 - fy), wt[2] = (1 - fx) * fy, wt[3] = fx * fy;
}

template <class T>
void forward_kernel(const T* fmap, const T* uv, T* out, int64_t N, int64_t C, int64_t h, int64_t w, int64_t W,
                    int64_t H) {
  at::parallel_for(0, N, 256, [&](int64_t b, int64_t e) {
    for (int64_t n = b; n < e; ++n) {
      int64_t idx[4];
      T wt[4];
      corners<T>(uv[2 * n], uv[2 * n + 1], W, H, h, w, idx, wt);
      T* o = out + n * C;
      const T *f0 = fmap + idx[0] * C, *f1 = fmap + idx[1] * C, *f2 = fmap + idx[2] * C, *f3 = fmap + idx[3] * C;
#pragma omp simd  // rows never overlap the map; without this GCC's alias checks stop it vectorizing
      for (int64_t c = 0; c < C; ++c) o[c] = wt[0] * f0[c] + wt[1] * f1[c] + wt[2] * f2[c] + wt[3] * f3[c];
    }
  });
}

// Texel-major gradient accumulation: the 4N (point, corner) entries are bucketed by texel (counting
// sort, point order kept), then each texel sums w * grad[point] over its entries. Parallel over texels,
// no atomics, the same result for any thread count.
template <class T>
struct TexelScatter {
  std::vector<int64_t> start, entries;
  std::vector<T> weight;
  TexelScatter(const T* uv, int64_t N, int64_t h, int64_t w, int64_t W, int64_t H) {
    const int64_t texels = h * w;
    std::vector<int64_t> index(static_cast<size_t>(4 * N));
    weight.resize(static_cast<size_t>(4 * N));
    at::parallel_for(0, N, 1024, [&](int64_t b, int64_t e) {
      for (int64_t n = b; n < e; ++n) {
        int64_t idx[4];
        T wt[4];
        corners<T>(uv[2 * n], uv[2 * n + 1], W, H, h, w, idx, wt);
        for (int k = 0; k < 4; ++k) index[4 * n + k] = idx[k], weight[4 * n + k] = wt[k];
      }
    });
    start.assign(static_cast<size_t>(texels) + 1, 0);
    entries.resize(static_cast<size_t>(4 * N));
    for (int64_t q = 0; q < 4 * N; ++q) ++start[index[q] + 1];
    for (int64_t t = 0; t < texels; ++t) start[t + 1] += start[t];
    std::vector<int64_t> fill(start.begin(), start.end() - 1);
    for (int64_t q = 0; q < 4 * N; ++q) entries[fill[index[q]]++] = q;
  }
  // grad_map [texels, C] (channel-last) = sum over entries of weight * grad_rows[point] ([N, C]).
  void apply(const T* grad_rows, T* grad_map, int64_t C) const {
    const int64_t texels = static_cast<int64_t>(start.size()) - 1;
    at::parallel_for(0, texels, 16, [&](int64_t b, int64_t e) {
      for (int64_t t = b; t < e; ++t) {
        T* g = grad_map + t * C;
        std::fill(g, g + C, T(0));
        for (int64_t s = start[t]; s < start[t + 1]; ++s) {
          const int64_t q = entries[s];
          const T wq = weight[q];
          const T* go = grad_rows + (q / 4) * C;
          for (int64_t c = 0; c < C; ++c) g[c] += wq * go[c];
        }
      }
    });
  }
};

template <class T>
void backward_kernel(const T* grad_out, const T* uv, T* grad_map, int64_t N, int64_t C, int64_t h, int64_t w, int64_t W,
                     int64_t H) {
  TexelScatter<T>(uv, N, h, w, W, H).apply(grad_out, grad_map, C);
}

class SampleFeatures : public torch::autograd::Function<SampleFeatures> {
 public:
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& features,
                               const torch::Tensor& uv, int64_t width, int64_t height) {
    const int64_t C = features.size(1), h = features.size(2), w = features.size(3), N = uv.size(0);
    auto fmap = features[0].permute({1, 2, 0}).contiguous();  // [h,w,C]
    auto points = uv.to(features.scalar_type()).contiguous();
    auto out = torch::empty({N, C}, features.options());
    AT_DISPATCH_FLOATING_TYPES(features.scalar_type(), "sample_features", [&] {
      forward_kernel<scalar_t>(fmap.data_ptr<scalar_t>(), points.data_ptr<scalar_t>(), out.data_ptr<scalar_t>(), N, C,
                               h, w, width, height);
    });
    ctx->save_for_backward({points});
    ctx->saved_data["shape"] = std::vector<int64_t>{C, h, w, width, height};
    return out;
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const auto points = ctx->get_saved_variables()[0];
    const auto shape = ctx->saved_data["shape"].toIntVector();
    const int64_t C = shape[0], h = shape[1], w = shape[2];
    auto go = grads[0].contiguous();
    auto gmap = torch::empty({h, w, C}, go.options());
    AT_DISPATCH_FLOATING_TYPES(go.scalar_type(), "sample_features_backward", [&] {
      backward_kernel<scalar_t>(go.data_ptr<scalar_t>(), points.data_ptr<scalar_t>(), gmap.data_ptr<scalar_t>(),
                                points.size(0), C, h, w, shape[3], shape[4]);
    });
    return {gmap.permute({2, 0, 1}).unsqueeze(0), torch::Tensor(), torch::Tensor(), torch::Tensor()};
  }
};

// ---- gated fusion fused with its four queries

// The gate 1 / (1 + e^−s) in two steps, each a loop of its own. float: e^−s as 2^y, y = −s·log2 e clamped to
// ±126 (beyond that the gate is 0 or 1 in float), through exp2_poly (relative error about 1e-7); double (the
// tests' precision): std::exp. In one loop GCC threads the clamp's constant arms through the polynomial, and the
// branches it makes keep the loop scalar; apart, both vectorize.
inline float gate_exponent(float s) {
  return std::min(std::max(s * -1.44269504f, -126.0f), 126.0f);
}
inline double gate_exponent(double s) {
  return -s;
}
inline float gate_from_exponent(float y) {
  return 1.0f / (1.0f + exp2_poly(y));
}
inline double gate_from_exponent(double y) {
  return 1.0 / (1.0 + std::exp(y));
}

// For each support n and channel c: the four bilinear queries and the gate, handed to visit(n, c, fd, fc, g).
// The forward and the backward share it, so the backward recomputes exactly the forward's values. A support's
// channels go through four passes (queries, gate exponents, gates, visits), each a loop over contiguous channels that
// vectorizes.
template <class T, class Visit>
void for_each_gated_query(const T* d, const T* gd, const T* cp, const T* gc, const T* uv, int64_t N, int64_t C,
                          int64_t hd, int64_t wd, int64_t hc, int64_t wc, int64_t W, int64_t H, const Visit& visit) {
  at::parallel_for(0, N, 256, [&](int64_t b, int64_t e) {
    std::vector<T> row(size_t(3 * C));  // fd, fc and the gate's input, then the gate, of one support
    T* const fd = row.data();
    T* const fc = fd + C;
    T* const g = fc + C;
    for (int64_t n = b; n < e; ++n) {
      int64_t id[4], ic[4];
      T wdt[4], wct[4];
      corners<T>(uv[2 * n], uv[2 * n + 1], W, H, hd, wd, id, wdt);
      corners<T>(uv[2 * n], uv[2 * n + 1], W, H, hc, wc, ic, wct);
      const T *d0 = d + id[0] * C, *d1 = d + id[1] * C, *d2 = d + id[2] * C, *d3 = d + id[3] * C;
      const T *gd0 = gd + id[0] * C, *gd1 = gd + id[1] * C, *gd2 = gd + id[2] * C, *gd3 = gd + id[3] * C;
      const T *c0 = cp + ic[0] * C, *c1 = cp + ic[1] * C, *c2 = cp + ic[2] * C, *c3 = cp + ic[3] * C;
      const T *gc0 = gc + ic[0] * C, *gc1 = gc + ic[1] * C, *gc2 = gc + ic[2] * C, *gc3 = gc + ic[3] * C;
      // omp simd: 3 outputs against 16 inputs are too many alias checks for GCC to vectorize the loops itself.
#pragma omp simd
      for (int64_t c = 0; c < C; ++c) {  // the sums in the order k = 0..3, from 0, as one loop over k would
        fd[c] = T(0) + wdt[0] * d0[c] + wdt[1] * d1[c] + wdt[2] * d2[c] + wdt[3] * d3[c];
        fc[c] = T(0) + wct[0] * c0[c] + wct[1] * c1[c] + wct[2] * c2[c] + wct[3] * c3[c];
        const T g1 = T(0) + wdt[0] * gd0[c] + wdt[1] * gd1[c] + wdt[2] * gd2[c] + wdt[3] * gd3[c];
        const T g2 = T(0) + wct[0] * gc0[c] + wct[1] * gc1[c] + wct[2] * gc2[c] + wct[3] * gc3[c];
        g[c] = g1 + g2;
      }
#pragma omp simd
      for (int64_t c = 0; c < C; ++c) g[c] = gate_exponent(g[c]);
#pragma omp simd
      for (int64_t c = 0; c < C; ++c) g[c] = gate_from_exponent(g[c]);
      for (int64_t c = 0; c < C; ++c) visit(n, c, fd[c], fc[c], g[c]);
    }
  });
}

template <class T>
void gated_forward(const T* d, const T* gd, const T* cp, const T* gc, const T* uv, T* out, int64_t N, int64_t C,
                   int64_t hd, int64_t wd, int64_t hc, int64_t wc, int64_t W, int64_t H) {
  for_each_gated_query(d, gd, cp, gc, uv, N, C, hd, wd, hc, wc, W, H,
                       [&](int64_t n, int64_t c, T fd, T fc, T g) { out[n * C + c] = g * fd + (T(1) - g) * fc; });
}

// Per-support gradients of the four queried values (recomputed from the maps, nothing stored).
template <class T>
void gated_backward_rows(const T* d, const T* gd, const T* cp, const T* gc, const T* uv, const T* go, T* r_d, T* r_c,
                         T* r_g, int64_t N, int64_t C, int64_t hd, int64_t wd, int64_t hc, int64_t wc, int64_t W,
                         int64_t H) {
  for_each_gated_query(d, gd, cp, gc, uv, N, C, hd, wd, hc, wc, W, H, [&](int64_t n, int64_t c, T fd, T fc, T g) {
    const T dh = go[n * C + c];
    r_d[n * C + c] = g * dh;                           // d h / d fd
    r_c[n * C + c] = (T(1) - g) * dh;                  // d h / d fc
    r_g[n * C + c] = (fd - fc) * dh * g * (T(1) - g);  // d h / d (g1 + g2)
  });
}

class GatedSample : public torch::autograd::Function<GatedSample> {
 public:
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& dino,
                               const torch::Tensor& gate_dino, const torch::Tensor& cnn_proj,
                               const torch::Tensor& gate_cnn, const torch::Tensor& uv, int64_t width, int64_t height) {
    const int64_t C = dino.size(1), N = uv.size(0);
    auto last = [](const torch::Tensor& m) { return m[0].permute({1, 2, 0}).contiguous(); };
    auto d = last(dino), gd = last(gate_dino), cp = last(cnn_proj), gc = last(gate_cnn);
    auto points = uv.to(dino.scalar_type()).contiguous();
    auto out = torch::empty({N, C}, dino.options());
    AT_DISPATCH_FLOATING_TYPES(dino.scalar_type(), "gated_sample", [&] {
      gated_forward<scalar_t>(d.data_ptr<scalar_t>(), gd.data_ptr<scalar_t>(), cp.data_ptr<scalar_t>(),
                              gc.data_ptr<scalar_t>(), points.data_ptr<scalar_t>(), out.data_ptr<scalar_t>(), N, C,
                              dino.size(2), dino.size(3), cnn_proj.size(2), cnn_proj.size(3), width, height);
    });
    ctx->save_for_backward({d, gd, cp, gc, points});
    ctx->saved_data["shape"] =
        std::vector<int64_t>{C, dino.size(2), dino.size(3), cnn_proj.size(2), cnn_proj.size(3), width, height};
    return out;
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const auto saved = ctx->get_saved_variables();
    const auto& d = saved[0];
    const auto& gd = saved[1];
    const auto& cp = saved[2];
    const auto& gc = saved[3];
    const auto& points = saved[4];
    const auto sh = ctx->saved_data["shape"].toIntVector();
    const int64_t C = sh[0], hd = sh[1], wd = sh[2], hc = sh[3], wc = sh[4], W = sh[5], H = sh[6], N = points.size(0);
    auto go = grads[0].contiguous();
    auto r_d = torch::empty({N, C}, go.options()), r_c = torch::empty({N, C}, go.options()),
         r_g = torch::empty({N, C}, go.options());
    auto g_d = torch::empty({hd, wd, C}, go.options()), g_gd = torch::empty({hd, wd, C}, go.options());
    auto g_c = torch::empty({hc, wc, C}, go.options()), g_gc = torch::empty({hc, wc, C}, go.options());
    AT_DISPATCH_FLOATING_TYPES(go.scalar_type(), "gated_sample_backward", [&] {
      gated_backward_rows<scalar_t>(d.data_ptr<scalar_t>(), gd.data_ptr<scalar_t>(), cp.data_ptr<scalar_t>(),
                                    gc.data_ptr<scalar_t>(), points.data_ptr<scalar_t>(), go.data_ptr<scalar_t>(),
                                    r_d.data_ptr<scalar_t>(), r_c.data_ptr<scalar_t>(), r_g.data_ptr<scalar_t>(), N, C,
                                    hd, wd, hc, wc, W, H);
      const TexelScatter<scalar_t> sd(points.data_ptr<scalar_t>(), N, hd, wd, W, H),
          sc(points.data_ptr<scalar_t>(), N, hc, wc, W, H);
      sd.apply(r_d.data_ptr<scalar_t>(), g_d.data_ptr<scalar_t>(), C);
      sd.apply(r_g.data_ptr<scalar_t>(), g_gd.data_ptr<scalar_t>(), C);
      sc.apply(r_c.data_ptr<scalar_t>(), g_c.data_ptr<scalar_t>(), C);
      sc.apply(r_g.data_ptr<scalar_t>(), g_gc.data_ptr<scalar_t>(), C);
    });
    auto back = [](const torch::Tensor& m) { return m.permute({2, 0, 1}).unsqueeze(0); };
    return {back(g_d), back(g_gd), back(g_c), back(g_gc), torch::Tensor(), torch::Tensor(), torch::Tensor()};
  }
};

}  // namespace

torch::Tensor sample_features(const torch::Tensor& features, const torch::Tensor& uv, int64_t width, int64_t height) {
  ISPLAT_CHECK(features.dim() == 4 && features.size(0) == 1, "sample_features: features must be [1,C,h,w], got ",
               features.sizes());
  ISPLAT_CHECK(uv.dim() == 2 && uv.size(1) == 2, "sample_features: uv must be [N,2], got ", uv.sizes());
  ISPLAT_CHECK(width > 0 && height > 0, "sample_features: image size must be positive");
  return SampleFeatures::apply(features, uv.detach(), width, height);
}

torch::Tensor gated_sample(const torch::Tensor& dino, const torch::Tensor& gate_dino, const torch::Tensor& cnn_proj,
                           const torch::Tensor& gate_cnn, const torch::Tensor& uv, int64_t width, int64_t height) {
  ISPLAT_CHECK(dino.dim() == 4 && dino.size(0) == 1 && gate_dino.sizes() == dino.sizes(),
               "gated_sample: dino and gate_dino must be equal [1,C,h,w] maps, got ", dino.sizes(), " and ",
               gate_dino.sizes());
  ISPLAT_CHECK(cnn_proj.dim() == 4 && cnn_proj.size(0) == 1 && gate_cnn.sizes() == cnn_proj.sizes() &&
                   cnn_proj.size(1) == dino.size(1),
               "gated_sample: cnn_proj and gate_cnn must be equal [1,C,h,w] maps with the dino's C, got ",
               cnn_proj.sizes(), " and ", gate_cnn.sizes());
  ISPLAT_CHECK(uv.dim() == 2 && uv.size(1) == 2, "gated_sample: uv must be [N,2], got ", uv.sizes());
  return GatedSample::apply(dino, gate_dino, cnn_proj, gate_cnn, uv.detach(), width, height);
}

}  // namespace isplat

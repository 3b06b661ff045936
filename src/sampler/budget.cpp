// Budgets: fixed, per pixel, per steradian of valid surface, or by the image's and surface's detail.
#include "sampler/budget.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "geometry/camera_torch.h"
#include "geometry/pixel_mask.h"

namespace isplat {
namespace sampling {

SamplerOptions without_fill(SamplerOptions o) {
  o.fill_px = 0;
  return o;
}

FilledDepth fill_holes(const torch::Tensor& depth, const torch::Tensor& valid, const SamplerOptions& o) {
  return fill_depth_holes(depth, valid, o.fill_px);
}

std::vector<float> detail_weights(const Grid& g, const SamplerOptions& o) {
  const int64_t H = g.H, W = g.W, HW = H * W;
  auto ok = [&](int64_t i, int64_t j) { return i >= 0 && j >= 0 && i < H && j < W && g.valid[i * W + j] != 0.0f; };
  // Detail per pixel: the largest colour gradient (sRGB per pixel) plus the surface's curvature, measured
  // as |Laplacian of inverse depth| relative to the inverse depth (0 on any plane, large at creases and
  // depth edges).
  std::vector<float> detail(static_cast<size_t>(HW), 0.0f);
  for_each_row(H, [&](int64_t i) {
    for (int64_t j = 0; j < W; ++j) {
      if (!ok(i, j)) continue;
      const int64_t jl = ok(i, j - 1) ? j - 1 : j, jr = ok(i, j + 1) ? j + 1 : j;
      const int64_t iu = ok(i - 1, j) ? i - 1 : i, id = ok(i + 1, j) ? i + 1 : i;
      float colour = 0;
      for (int c = 0; c < 3; ++c) {
        const float* m = g.image + c * HW;
        const float gx = (m[i * W + jr] - m[i * W + jl]) / float(std::max<int64_t>(1, jr - jl));
        const float gy = (m[id * W + j] - m[iu * W + j]) / float(std::max<int64_t>(1, id - iu));
        colour = std::max(colour, std::sqrt(gx * gx + gy * gy));
      }
      const double inv = 1.0 / g.depth[i * W + j];
      double lap = 0;
      if (jl != j && jr != j) lap += 1.0 / g.depth[i * W + jl] + 1.0 / g.depth[i * W + jr] - 2 * inv;
      if (iu != i && id != i) lap += 1.0 / g.depth[iu * W + j] + 1.0 / g.depth[id * W + j] - 2 * inv;
      detail[i * W + j] = colour + static_cast<float>(std::min(1.0, std::abs(lap) / inv));
    }
  });
  // Block means over valid pixels, mapped to the weight.
  const int64_t b = o.detail_block, bh = (H + b - 1) / b, bw = (W + b - 1) / b;
  std::vector<float> weight(static_cast<size_t>(HW), 0.0f);
  at::parallel_for(0, bh, 1, [&](int64_t b0, int64_t b1) {
    for (int64_t by = b0; by < b1; ++by)
      for (int64_t bx = 0; bx < bw; ++bx) {
        double sum = 0;
        int64_t count = 0;
        for (int64_t i = by * b; i < std::min(H, (by + 1) * b); ++i)
          for (int64_t j = bx * b; j < std::min(W, (bx + 1) * b); ++j)
            if (ok(i, j)) sum += detail[i * W + j], ++count;
        if (count == 0) continue;
        const float w =
            static_cast<float>(o.detail_floor + (1.0 - o.detail_floor) * std::min(1.0, sum / count / o.detail_ref));
        for (int64_t i = by * b; i < std::min(H, (by + 1) * b); ++i)
          for (int64_t j = bx * b; j < std::min(W, (bx + 1) * b); ++j)
            if (ok(i, j)) weight[i * W + j] = w;
      }
  });
  return weight;
}

namespace {

int64_t clamp_budget(const SamplerOptions& o, int64_t n) {
  return std::clamp(n, o.min_budget, std::max(o.min_budget, o.max_budget));
}

}  // namespace

int64_t detail_budget(const SamplerOptions& o, const std::vector<float>& weight) {
  double sum = 0;
  for (float w : weight) sum += w;
  return clamp_budget(o, static_cast<int64_t>(std::llround(o.density * sum)));
}

}  // namespace sampling

using namespace sampling;

torch::Tensor detail_weights(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& image,
                             const SamplerOptions& options) {
  if (options.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, options);
    return detail_weights(f.depth, f.valid, image, without_fill(options));
  }
  torch::Tensor dk, vk, ik;
  const Grid g = make_grid(depth, valid, torch::eye(3), image, dk, vk, ik);
  std::vector<float> w = detail_weights(g, options);
  return torch::from_blob(w.data(), {g.H, g.W}, torch::kFloat32).clone();
}

int64_t resolve_budget(const SamplerOptions& o, const torch::Tensor& depth, const torch::Tensor& valid,
                       const torch::Tensor& K, const torch::Tensor& image) {
  if (o.budget_mode == "fixed") return o.budget;
  if (o.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, o);
    return resolve_budget(without_fill(o), f.depth, f.valid, K, image);
  }
  if (o.budget_mode == "detail") {
    ISPLAT_CHECK(image.defined(), "sampler: budget_mode = detail needs the image");
    torch::Tensor dk, vk, ik;
    return detail_budget(o, detail_weights(make_grid(depth, valid, K, image, dk, vk, ik), o));
  }
  int64_t n = 0;
  if (o.budget_mode == "per_pixel") {
    n = static_cast<int64_t>(std::llround(o.density * depth.size(0) * depth.size(1)));
  } else if (o.budget_mode == "solid_angle") {
    // Solid angle of the valid pixels: each pixel subtends ~ cos^3(theta) / (fx fy) steradians.
    auto Kd = K.to(torch::kFloat64);
    const double fx = Kd[0][0].item<double>(), fy = Kd[1][1].item<double>(), cx = Kd[0][2].item<double>(),
                 cy = Kd[1][2].item<double>();
    const auto uv = pixel_centers(depth.size(0), depth.size(1), torch::kFloat64);
    auto x = (uv.select(-1, 0) - cx) / fx, y = (uv.select(-1, 1) - cy) / fy;
    auto cos3 = torch::pow(1.0 + x * x + y * y, -1.5);
    auto ok = usable_depth(depth, valid).to(torch::kFloat64);
    const double omega = (cos3 * ok).sum().item<double>() / (fx * fy);
    n = static_cast<int64_t>(std::llround(o.density * omega));
  } else {
    fail("sampler.budget_mode: unknown '", o.budget_mode, "'");
  }
  return clamp_budget(o, n);
}

}  // namespace isplat

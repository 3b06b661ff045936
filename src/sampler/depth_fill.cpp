// Push-pull hole filling in log depth, limited to a Chebyshev distance from usable depth.
#include "sampler/depth_fill.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "geometry/camera_torch.h"

namespace isplat {
namespace {

// Chebyshev distance of every pixel to the nearest usable one (two raster passes; exact for this metric).
std::vector<int64_t> chebyshev_distance(const float* ok, int64_t H, int64_t W) {
  const int64_t far = std::numeric_limits<int64_t>::max() / 2;
  std::vector<int64_t> d(static_cast<size_t>(H * W));
  for (int64_t p = 0; p < H * W; ++p) d[p] = ok[p] != 0.0f ? 0 : far;
  auto relax = [&](int64_t i, int64_t j, int64_t di, int64_t dj) {
    const int64_t a = i + di, b = j + dj;
    if (a < 0 || a >= H || b < 0 || b >= W) return;
    d[i * W + j] = std::min(d[i * W + j], d[a * W + b] + 1);
  };
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) relax(i, j, -1, -1), relax(i, j, -1, 0), relax(i, j, -1, 1), relax(i, j, 0, -1);
  for (int64_t i = H - 1; i >= 0; --i)
    for (int64_t j = W - 1; j >= 0; --j) relax(i, j, 1, 1), relax(i, j, 1, 0), relax(i, j, 1, -1), relax(i, j, 0, 1);
  return d;
}

struct Level {
  int64_t H, W;
  std::vector<double> value, weight;  // log depth; confidence in [0, 1]
};

// Linear interpolation of a coarse level at the centre of fine pixel (i, j) (half-resolution grid).
double upsample(const Level& c, int64_t i, int64_t j) {
  const double y = std::clamp((i + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(c.H - 1));
  const double x = std::clamp((j + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(c.W - 1));
  const int64_t y0 = static_cast<int64_t>(y), x0 = static_cast<int64_t>(x);
  const int64_t y1 = std::min(y0 + 1, c.H - 1), x1 = std::min(x0 + 1, c.W - 1);
  const double fy = y - y0, fx = x - x0;
  const auto at = [&](int64_t a, int64_t b) { return c.value[a * c.W + b]; };
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x1)) + fy * ((1 - fx) * at(y1, x0) + fx * at(y1, x1));
}

}  // namespace

FilledDepth fill_depth_holes(const torch::Tensor& depth, const torch::Tensor& valid, int64_t max_px) {
  ISPLAT_CHECK(depth.dim() == 2, "depth fill: depth must be [H, W], got ", depth.sizes());
  ISPLAT_CHECK(valid.sizes() == depth.sizes(), "depth fill: valid ", valid.sizes(), " differs from depth ",
               depth.sizes());
  ISPLAT_CHECK(max_px >= 0, "depth fill: max_px must be >= 0, got ", max_px);
  torch::NoGradGuard no_grad;
  const torch::Tensor ok_t = usable_depth(depth.detach(), valid.detach()).to(torch::kFloat32).contiguous();
  FilledDepth out;
  out.depth = torch::where(ok_t > 0, depth.detach().to(torch::kFloat32), torch::zeros({}, torch::kFloat32))
                  .contiguous()
                  .clone();
  out.valid = ok_t.clone();
  const int64_t H = depth.size(0), W = depth.size(1);
  const float* ok = ok_t.data_ptr<float>();
  float* z = out.depth.data_ptr<float>();
  float* v = out.valid.data_ptr<float>();
  if (max_px == 0 || H * W == 0 || ok_t.sum().item<double>() == 0) return out;

  // Pull: each coarser level holds the confidence-weighted mean of its 2x2 children.
  std::vector<Level> levels(1);
  levels[0] = {H, W, std::vector<double>(static_cast<size_t>(H * W), 0.0),
               std::vector<double>(static_cast<size_t>(H * W), 0.0)};
  for (int64_t p = 0; p < H * W; ++p)
    if (ok[p] != 0.0f) levels[0].value[p] = std::log(static_cast<double>(z[p])), levels[0].weight[p] = 1.0;
  while (levels.back().H > 1 || levels.back().W > 1) {
    const Level& f = levels.back();
    Level c{(f.H + 1) / 2, (f.W + 1) / 2, {}, {}};
    c.value.assign(static_cast<size_t>(c.H * c.W), 0.0);
    c.weight.assign(static_cast<size_t>(c.H * c.W), 0.0);
    for (int64_t i = 0; i < c.H; ++i)
      for (int64_t j = 0; j < c.W; ++j) {
        double s = 0, t = 0;
        for (int64_t a = 2 * i; a < std::min(2 * i + 2, f.H); ++a)
          for (int64_t b = 2 * j; b < std::min(2 * j + 2, f.W); ++b) {
            s += f.weight[a * f.W + b] * f.value[a * f.W + b];
            t += f.weight[a * f.W + b];
          }
        c.value[i * c.W + j] = t > 0 ? s / t : 0.0;
        c.weight[i * c.W + j] = std::min(1.0, t);
      }
    levels.push_back(std::move(c));
  }
  // Push: from the top down, each level's uncertain part takes the interpolated coarser value.
  for (size_t l = levels.size() - 1; l-- > 0;) {
    Level& f = levels[l];
    const Level& c = levels[l + 1];
    for (int64_t i = 0; i < f.H; ++i)
      for (int64_t j = 0; j < f.W; ++j) {
        double& w = f.weight[i * f.W + j];
        if (w < 1.0) f.value[i * f.W + j] = w * f.value[i * f.W + j] + (1.0 - w) * upsample(c, i, j);
        w = 1.0;
      }
  }
  const std::vector<int64_t> dist = chebyshev_distance(ok, H, W);
  for (int64_t p = 0; p < H * W; ++p)
    if (ok[p] == 0.0f && dist[p] <= max_px) {
      z[p] = static_cast<float>(std::exp(levels[0].value[p]));
      v[p] = 1.0f;
      ++out.filled;
    }
  return out;
}

}  // namespace isplat

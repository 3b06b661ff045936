// Push-pull hole filling in log depth, limited to a Chebyshev distance from usable depth.
#include "sampler/depth_fill.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "geometry/camera_torch.h"
#include "geometry/pixel_mask.h"

namespace isplat {
namespace {

struct Level {
  int64_t H, W;
  std::vector<double> log_depth;
  std::vector<char> covered;  // the cell holds usable depth (at the finest level) or a child that does
};

// Bilinear interpolation of a half-resolution level at the centre of fine pixel (i, j). (An odd-sized level's
// last cell has one child, so near the bottom and right borders the fill leans half a pixel; it stays a blend.)
double upsample(const Level& coarse, int64_t i, int64_t j) {
  const double y = std::clamp((i + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(coarse.H - 1));
  const double x = std::clamp((j + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(coarse.W - 1));
  const int64_t y0 = static_cast<int64_t>(y), x0 = static_cast<int64_t>(x);
  const int64_t y1 = std::min(y0 + 1, coarse.H - 1), x1 = std::min(x0 + 1, coarse.W - 1);
  const double fy = y - y0, fx = x - x0;
  const auto at = [&](int64_t a, int64_t b) { return coarse.log_depth[a * coarse.W + b]; };
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x1)) + fy * ((1 - fx) * at(y1, x0) + fx * at(y1, x1));
}

}  // namespace

FilledDepth fill_depth_holes(const torch::Tensor& depth, const torch::Tensor& valid, int64_t max_px) {
  ISPLAT_CHECK(depth.dim() == 2, "depth fill: depth must be [H, W], got ", depth.sizes());
  ISPLAT_CHECK(valid.sizes() == depth.sizes(), "depth fill: valid ", valid.sizes(), " differs from depth ",
               depth.sizes());
  ISPLAT_CHECK(max_px >= 0, "depth fill: max_px must be >= 0, got ", max_px);
  ISPLAT_CHECK(depth.device().is_cpu() && valid.device().is_cpu(), "depth fill: depth and valid must be on the CPU");
  torch::NoGradGuard no_grad;
  const torch::Tensor usable_t = usable_depth(depth.detach(), valid.detach()).to(torch::kFloat32).contiguous();
  FilledDepth out;
  out.depth = torch::where(usable_t > 0, depth.detach().to(torch::kFloat32), torch::zeros({}, torch::kFloat32))
                  .contiguous()
                  .clone();
  out.valid = usable_t.clone();
  const int64_t H = depth.size(0), W = depth.size(1);
  const float* usable = usable_t.data_ptr<float>();
  float* out_depth = out.depth.data_ptr<float>();
  float* out_valid = out.valid.data_ptr<float>();
  if (max_px == 0 || H * W == 0 || usable_t.sum().item<double>() == 0) return out;

  // Pull: each coarser cell holds the mean log depth of its covered 2x2 children (blending in log depth keeps a
  // hole between 1 m and 100 m near 10 m, not 50 m).
  std::vector<Level> levels(1);
  levels[0] = {H, W, std::vector<double>(static_cast<size_t>(H * W), 0.0), std::vector<char>(H * W, 0)};
  for (int64_t p = 0; p < H * W; ++p)
    if (usable[p] != 0.0f)
      levels[0].log_depth[p] = std::log(static_cast<double>(out_depth[p])), levels[0].covered[p] = 1;
  while (levels.back().H > 1 || levels.back().W > 1) {
    const Level& fine = levels.back();
    Level coarse{(fine.H + 1) / 2, (fine.W + 1) / 2, {}, {}};
    coarse.log_depth.assign(static_cast<size_t>(coarse.H * coarse.W), 0.0);
    coarse.covered.assign(static_cast<size_t>(coarse.H * coarse.W), 0);
    for (int64_t i = 0; i < coarse.H; ++i)
      for (int64_t j = 0; j < coarse.W; ++j) {
        double sum = 0;
        int count = 0;
        for (int64_t a = 2 * i; a < std::min(2 * i + 2, fine.H); ++a)
          for (int64_t b = 2 * j; b < std::min(2 * j + 2, fine.W); ++b)
            if (fine.covered[a * fine.W + b]) sum += fine.log_depth[a * fine.W + b], ++count;
        coarse.log_depth[i * coarse.W + j] = count > 0 ? sum / count : 0.0;
        coarse.covered[i * coarse.W + j] = count > 0;
      }
    levels.push_back(std::move(coarse));  // `fine` is not used after this: the push may reallocate
  }
  // Push: from the top down, each uncovered cell takes the interpolated value of the (complete) coarser level.
  for (size_t l = levels.size() - 1; l-- > 0;) {
    Level& fine = levels[l];
    for (int64_t i = 0; i < fine.H; ++i)
      for (int64_t j = 0; j < fine.W; ++j)
        if (!fine.covered[i * fine.W + j]) fine.log_depth[i * fine.W + j] = upsample(levels[l + 1], i, j);
  }
  std::vector<uint8_t> reachable(static_cast<size_t>(H * W));  // within max_px (Chebyshev) of usable depth
  for (int64_t p = 0; p < H * W; ++p) reachable[p] = usable[p] != 0.0f;
  reachable = dilate_square(reachable, H, W, max_px);
  std::vector<double>& fill = levels[0].log_depth;
  for (int64_t p = 0; p < H * W; ++p)
    if (usable[p] == 0.0f && reachable[p]) {
      out_depth[p] = static_cast<float>(std::exp(fill[p]));
      out_valid[p] = 1.0f;
      ++out.filled;
    }
  return out;
}

}  // namespace isplat

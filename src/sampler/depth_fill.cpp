// Push-pull hole filling in log depth, limited to a Chebyshev distance from usable depth, with a far-side mode.
#include "sampler/depth_fill.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "geometry/camera_torch.h"
#include "geometry/pixel_mask.h"
#include "sampler/sampler.h"

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

// The far side of a hole at pixel (i, j). Along each of the 8 pixel directions, the first usable pixel within
// `reach` steps is a hit; its surface is extrapolated back to (i, j) linearly in inverse depth (exact on a
// plane), with the slope from the next usable pixel or the one after it along the ray (none across an edge).
// The near layer is the hits the sampler's discontinuity test does not separate from the nearest; the far layer
// is the nearest hit it does separate, with the hits not separated from that one (not the farthest surface: a ray
// through a gap between objects may reach a third). When a far layer exists and the hole is a strip at most
// `width` steps across (nearest near hit + nearest far hit along the 8 rays, so a strip of w missing pixels across
// an axis-aligned edge counts w + 1), the pixel takes the inverse-distance mean, in log depth, of the far layer.
// Otherwise it returns false and the blend stays: holes with no edge across them, and wide holes between
// surfaces, such as a receding street whose "far side" is a whole region.
bool far_side_log_depth(const float* usable, const float* depth, int64_t H, int64_t W, int64_t i, int64_t j,
                        int64_t reach, int64_t width, double& log_out) {
  static constexpr int kDi[8] = {-1, -1, -1, 0, 0, 1, 1, 1}, kDj[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
  double z[8], dist[8];
  bool sloped[8];
  int hits = 0;
  const auto ok = [&](int64_t a, int64_t b) { return a >= 0 && b >= 0 && a < H && b < W && usable[a * W + b] != 0; };
  for (int k = 0; k < 8; ++k)
    for (int64_t s = 1; s <= reach; ++s) {
      const int64_t a = i + s * kDi[k], b = j + s * kDj[k];
      if (a < 0 || b < 0 || a >= H || b >= W) break;
      if (usable[a * W + b] == 0) continue;  // still inside the hole
      const double iz = 1.0 / depth[a * W + b];
      double slope = 0;  // change of inverse depth per step outward along the ray
      sloped[hits] = false;
      for (int64_t t = 1; t <= 2; ++t)
        if (ok(a + t * kDi[k], b + t * kDj[k])) {
          const double iz2 = 1.0 / depth[(a + t * kDi[k]) * W + (b + t * kDj[k])];
          if (!depths_apart(1.0 / iz, 1.0 / iz2)) slope = (iz2 - iz) / t, sloped[hits] = true;
          break;
        }
      // Back to (i, j), s steps inward; within a factor of 2 of the hit, so a curved surface cannot run away.
      z[hits] = 1.0 / std::clamp(iz - s * slope, 0.5 * iz, 2.0 * iz);
      dist[hits++] = s * ((kDi[k] != 0 && kDj[k] != 0) ? std::sqrt(2.0) : 1.0);
      break;
    }
  if (hits < 2) return false;
  const double znear = *std::min_element(z, z + hits);
  double zfar = 0, near_dist = 1e30, far_dist = 1e30;
  for (int k = 0; k < hits; ++k)
    if (depths_apart(z[k], znear) && (zfar == 0 || z[k] < zfar)) zfar = z[k];
  if (zfar == 0) return false;      // no edge across the hole
  for (int k = 0; k < hits; ++k) {  // a third surface, apart from both layers, counts in neither
    if (!depths_apart(z[k], znear))
      near_dist = std::min(near_dist, dist[k]);
    else if (!depths_apart(z[k], zfar))
      far_dist = std::min(far_dist, dist[k]);
  }
  if (near_dist + far_dist > width) return false;
  // The far layer's hits whose surface could be extrapolated; those without a slope (at the image border, next
  // to another hole or edge) only when there is no other.
  double sum = 0, wsum = 0;
  for (int pass = 0; pass < 2 && wsum == 0; ++pass)
    for (int k = 0; k < hits; ++k)
      if ((sloped[k] || pass == 1) && !depths_apart(z[k], zfar)) sum += std::log(z[k]) / dist[k], wsum += 1 / dist[k];
  log_out = sum / wsum;  // the hit zfar counts in the second pass
  return true;
}

}  // namespace

FilledDepth fill_depth_holes(const torch::Tensor& depth, const torch::Tensor& valid, int64_t max_px,
                             int64_t far_width) {
  ISPLAT_CHECK(depth.dim() == 2, "depth fill: depth must be [H, W], got ", depth.sizes());
  ISPLAT_CHECK(valid.sizes() == depth.sizes(), "depth fill: valid ", valid.sizes(), " differs from depth ",
               depth.sizes());
  ISPLAT_CHECK(max_px >= 0, "depth fill: max_px must be >= 0, got ", max_px);
  ISPLAT_CHECK(far_width >= 0, "depth fill: far_width must be >= 0, got ", far_width);
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
  if (far_width > 0) {  // reads only the usable input, so rows are independent
    at::parallel_for(0, H, 8, [&](int64_t r0, int64_t r1) {
      for (int64_t i = r0; i < r1; ++i)
        for (int64_t j = 0; j < W; ++j)
          if (usable[i * W + j] == 0.0f && reachable[i * W + j])
            far_side_log_depth(usable, out_depth, H, W, i, j, max_px + 1, far_width, fill[i * W + j]);
    });
  }
  for (int64_t p = 0; p < H * W; ++p)
    if (usable[p] == 0.0f && reachable[p]) {
      out_depth[p] = static_cast<float>(std::exp(fill[p]));
      out_valid[p] = 1.0f;
      ++out.filled;
    }
  return out;
}

}  // namespace isplat

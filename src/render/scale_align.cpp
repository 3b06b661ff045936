// Median-ratio scale fit of a rendered prediction against reference depth samples, and the scaling about a camera.
#include "render/scale_align.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"

namespace isplat {

torch::Tensor depth_samples(const torch::Tensor& depth, const torch::Tensor& valid) {
  ISPLAT_CHECK(depth.dim() == 2 && valid.sizes() == depth.sizes(),
               "scale alignment: depth and valid must be [H,W], got ", depth.sizes(), " and ", valid.sizes());
  const auto z = depth.to(torch::kFloat32);
  const auto ok = (valid > 0).logical_and(z > 0).logical_and(torch::isfinite(z));
  const auto idx = torch::nonzero(ok);  // [P,2] (row, col)
  const auto uv = idx.flip({1}).to(torch::kFloat32) + 0.5;
  return torch::cat({uv, z.index({ok}).unsqueeze(1)}, 1).contiguous();
}

ScaleFit fit_scene_scale(const Gaussians& scene, const Camera& camera, const torch::Tensor& samples,
                         const RenderOptions& options) {
  ScaleFit fit;
  if (!samples.defined() || samples.numel() == 0 || scene.count() == 0) return fit;
  ISPLAT_CHECK(samples.dim() == 2 && samples.size(1) == 3, "scale alignment: samples must be [P,3] (u, v, z), got ",
               samples.sizes());
  RenderMaps maps;
  maps.normals = false;
  maps.median_depth = true;
  const RenderOutput r = render(scene, camera, options, maps);
  const auto rendered = r.median_depth.view({camera.height, camera.width}).to(torch::kFloat64);
  const auto s = samples.to(torch::kFloat64);
  const auto col = torch::floor(s.select(1, 0)).to(torch::kLong), row = torch::floor(s.select(1, 1)).to(torch::kLong);
  const auto z = s.select(1, 2);
  const auto inside =
      (col >= 0) & (col < camera.width) & (row >= 0) & (row < camera.height) & (z > 0) & torch::isfinite(z);
  const auto c = col.index({inside}), rr = row.index({inside}), zr = z.index({inside});
  const auto zp = rendered.index({rr, c});
  const auto shown = zp > 0;  // median depth is 0 where alpha < 0.5
  fit.samples = shown.sum().item<int64_t>();
  if (fit.samples == 0) return fit;
  // The lower median: an element of the set, so the same samples at another scale give exactly that scale's factor.
  fit.factor = (zr.index({shown}) / zp.index({shown})).median().item<double>();
  ISPLAT_CHECK(std::isfinite(fit.factor) && fit.factor > 0, "scale alignment: the fitted factor ", fit.factor,
               " is not a positive number");
  return fit;
}

Gaussians scale_about_camera(const Gaussians& g, const Camera& camera, double factor) {
  ISPLAT_CHECK(std::isfinite(factor) && factor > 0, "scale alignment: factor ", factor, " is not a positive number");
  ISPLAT_CHECK(!g.batched() && camera.batch() == 0, "scale alignment: one unbatched scene and camera");
  if (factor == 1.0) return g;
  const auto T = camera.T_cw.to(torch::kFloat64);
  const auto R = T.slice(0, 0, 3).slice(1, 0, 3), t = T.slice(0, 0, 3).select(1, 3);
  const auto centre = -torch::matmul(R.t(), t);  // the camera centre in the world frame
  const auto means = (centre + factor * (g.means.to(torch::kFloat64) - centre)).to(g.means.scalar_type());
  return {means, g.scales * factor, g.quats, g.colors, g.opacities};
}

}  // namespace isplat

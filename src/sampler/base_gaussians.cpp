// Scene normalization and base Gaussian attributes from supports.
#include "sampler/base_gaussians.h"

#include <torch/torch.h>

#include "core/error.h"

namespace isplat {

BaseGaussians make_base_gaussians(const Supports& s) {
  ISPLAT_CHECK(s.count() > 0, "base Gaussians: no supports");
  const double zmin = s.depth.min().item<double>();
  ISPLAT_CHECK(zmin > 0 && std::isfinite(zmin), "base Gaussians: support depth must be positive, min is ", zmin);
  BaseGaussians b;
  b.depth_factor = 1.0 / zmin;
  b.uv = s.uv;
  b.z_n = torch::clamp_max(s.depth * b.depth_factor, kMaxNormalizedDepth);
  b.scale_n = torch::sqrt(torch::clamp_min(s.area, 0.0)) * b.depth_factor;
  b.color = torch::clamp(s.color, 0.01, 0.99);
  b.opacity = torch::full({s.count()}, 0.5f);
  b.normal = s.normal;
  return b;
}

}  // namespace isplat

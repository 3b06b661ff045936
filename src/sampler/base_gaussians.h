// Base Gaussians at the supports, in the release's normalized scene units (DESIGN §3).
#pragma once
#include <torch/types.h>

#include "sampler/sampler.h"

namespace isplat {

struct BaseGaussians {
  torch::Tensor uv;           // [N,2] pixel coordinates
  torch::Tensor z_n;          // [N] normalized depth min(z * depth_factor, 100)
  torch::Tensor scale_n;      // [N] isotropic scale sqrt(area) * depth_factor
  torch::Tensor color;        // [N,3] sRGB clamped to [0.01, 0.99]
  torch::Tensor opacity;      // [N] 0.5
  torch::Tensor normal;       // [N,3] unit surface normal in the camera frame (composer.orientation = surface)
  double depth_factor = 1.0;  // 1 / min support depth
  int64_t count() const { return uv.size(0); }
};

constexpr double kMaxNormalizedDepth = 100.0;

BaseGaussians make_base_gaussians(const Supports& supports);

}  // namespace isplat

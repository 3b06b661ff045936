// sRGB transfer functions with the standard linear segment near black.
#include "geometry/color.h"

#include <torch/torch.h>

namespace isplat {

torch::Tensor srgb_to_linear(const torch::Tensor& x) {
  return torch::where(x <= 0.04045, x / 12.92, torch::pow((torch::clamp_min(x, 0.04045) + 0.055) / 1.055, 2.4));
}

torch::Tensor linear_to_srgb(const torch::Tensor& x) {
  auto c = torch::clamp_min(x, 0.0);
  return torch::where(c <= 0.0031308, c * 12.92, 1.055 * torch::pow(torch::clamp_min(c, 0.0031308), 1.0 / 2.4) - 0.055);
}

}  // namespace isplat

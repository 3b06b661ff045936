// sRGB <-> linear RGB transfer functions (IEC 61966-2-1), shared by the composer, the PLY writer and the viewers.
#pragma once
#include <torch/types.h>

namespace isplat {

torch::Tensor srgb_to_linear(const torch::Tensor& x);  // elementwise, any shape
torch::Tensor linear_to_srgb(const torch::Tensor& x);  // negative inputs clamp to 0

}  // namespace isplat

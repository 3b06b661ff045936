// Bilinear sampling of a feature map at support coordinates, as a custom autograd op with plain C++
// kernels: the semantics of grid_sample (bilinear, align_corners = false, border padding, coordinates
// clamped to +-(1 - 1e-6)), about 10x faster on CPU, deterministic, gradients to the features only.
#pragma once
#include <torch/types.h>

namespace isplat {

// features [1,C,h,w] (float32 or float64), uv [N,2] continuous pixel coordinates of a W x H image.
// Returns [N,C]. Supports are fixed inputs here, so uv receives no gradient.
torch::Tensor sample_features(const torch::Tensor& features, const torch::Tensor& uv, int64_t width, int64_t height);

}  // namespace isplat

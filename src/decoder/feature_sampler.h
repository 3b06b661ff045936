// Bilinear sampling of a feature map at support coordinates, as a custom autograd op with plain C++
// kernels: the semantics of grid_sample (bilinear, align_corners = false, border padding, coordinates
// clamped to +-(1 - 1e-6)), about 10x faster on CPU, deterministic, gradients to the features only.
#pragma once
#include <torch/types.h>

namespace isplat {

// features [1,C,h,w] (float32 or float64), uv [N,2] continuous pixel coordinates of a W x H image.
// Returns [N,C]. Supports are fixed inputs here, so uv receives no gradient.
torch::Tensor sample_features(const torch::Tensor& features, const torch::Tensor& uv, int64_t width, int64_t height);

// The decoder's gated fusion fused with the four feature queries it needs (DESIGN §3):
//   fd = q(dino), fc = q(cnn_proj), g = sigmoid(q(gate_dino) + q(gate_cnn)), h = g * fd + (1 - g) * fc,
// where q samples a map bilinearly at uv as sample_features does. dino/gate_dino share one resolution,
// cnn_proj/gate_cnn another; all have C channels. Returns h [N,C]; gradients go to all four maps.
// One pass over the supports instead of ten tensor-wide passes, and no [N,C] intermediates kept.
torch::Tensor gated_sample(const torch::Tensor& dino, const torch::Tensor& gate_dino, const torch::Tensor& cnn_proj,
                           const torch::Tensor& gate_cnn, const torch::Tensor& uv, int64_t width, int64_t height);

}  // namespace isplat

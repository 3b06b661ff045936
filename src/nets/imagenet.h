// ImageNet input normalization of [0,1] RGB, as DINO and torchvision networks expect it.
#pragma once
#include <torch/types.h>

namespace isplat {

inline constexpr float kImageNetMean[3] = {0.485f, 0.456f, 0.406f};
inline constexpr float kImageNetStd[3] = {0.229f, 0.224f, 0.225f};

// (x - mean) / std per channel of x [B,3,H,W], in x's dtype.
torch::Tensor imagenet_normalize(const torch::Tensor& x);
// The mean and std as float32 [1,3,1,1] tensors (e.g. for graph export).
torch::Tensor imagenet_mean();
torch::Tensor imagenet_std();

}  // namespace isplat

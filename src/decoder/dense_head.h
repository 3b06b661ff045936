// The dense head, the default decoder: per-pixel updates from both feature maps, read at each support's position.
#pragma once
#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/pimpl.h>

#include "encoder/features.h"

namespace isplat {

// DPT-style: fuses both maps at H/4, upsamples to full resolution and predicts 14 channels per pixel with a
// zero-initialized output. The paper's "w/o implicit decoder" row; with pixel-centre and silhouette supports it
// holds the photo better than the implicit decoder does (lab/2026-12-06-lpips-gap).
constexpr int64_t kDenseHeadWidth = 64;  // channels of its fused and refined maps (the last refinement has half)
struct DenseHeadImpl : torch::nn::Module {
  DenseHeadImpl(int64_t dino_dim, int64_t cnn_dim, int64_t width = kDenseHeadWidth);
  torch::Tensor forward(const EncoderFeatures& features, int64_t width, int64_t height);  // [1,14,H,W]
  torch::nn::Conv2d reduce{nullptr}, refine1{nullptr}, refine2{nullptr}, out{nullptr};
  int64_t dino_dim, cnn_dim;
};
TORCH_MODULE(DenseHead);

}  // namespace isplat

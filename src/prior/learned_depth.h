// The project's own small monocular depth network (encoder-decoder), trained with `task: depth`.
#pragma once
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/pimpl.h>

namespace isplat {

struct LearnedDepthNetImpl : torch::nn::Module {
  explicit LearnedDepthNetImpl(int64_t width = 32);
  // image [B,3,H,W] sRGB in [0,1] -> metric depth [B,1,H,W] (exp of the predicted log-depth).
  torch::Tensor forward(const torch::Tensor& image);
  torch::Tensor forward_log(const torch::Tensor& image);  // log-depth, for training losses
  torch::nn::ModuleList down{nullptr}, up{nullptr};
  torch::nn::Conv2d stem{nullptr}, head{nullptr};
};
TORCH_MODULE(LearnedDepthNet);

}  // namespace isplat

// The CNN branch (DESIGN §3): 7x7 stride-2 stem, 8 residual 3x3 blocks in 4 stages, multi-scale outputs
// upsampled to H/4 and fused by a 3x3 conv, projected by a 1x1 conv to 128 channels. Instance norm.
#pragma once
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

namespace isplat {

class ConfigVisitor;

struct CNNOptions {
  int64_t width = 32;  // stage widths are width x (1, 2, 3, 4)
  int64_t out_channels = 128;
  void visit(ConfigVisitor& v);
};

struct ResidualBlockImpl : torch::nn::Module {
  ResidualBlockImpl(int64_t in, int64_t out, int64_t stride);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, down{nullptr};
};
TORCH_MODULE(ResidualBlock);

struct CNNEncoderImpl : torch::nn::Module {
  explicit CNNEncoderImpl(const CNNOptions& options);
  // image [B,3,H,W] in [0,1] -> features [B,128,H/4,W/4].
  torch::Tensor forward(const torch::Tensor& image);
  torch::nn::Conv2d stem{nullptr}, fuse{nullptr}, project{nullptr};
  torch::nn::ModuleList blocks{nullptr};
  int64_t out_channels;
};
TORCH_MODULE(CNNEncoder);

// Instance norm without affine parameters (as the release), used by the CNN and dense head.
torch::Tensor instance_norm(const torch::Tensor& x);

}  // namespace isplat

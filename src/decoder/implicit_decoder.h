// The shared implicit decoder (DESIGN §3, release): query both feature maps bilinearly at each support,
// fuse them with a gate, and predict the 14-dim update through an MLP with a zero-initialized head. DecoderOptions
// choose between it and the dense head (decoder/dense_head.h).
#pragma once
#include <string>
#include <vector>

#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>

#include "encoder/features.h"

namespace isplat {

class ConfigVisitor;

struct DecoderOptions {
  std::string mode = "implicit";  // implicit | dense | none
  std::vector<int64_t> hidden;    // MLP widths; empty = [C, C/4, C/16] with C the fused width (ViT-L: 1024, 256, 64)
  int64_t chunk = 80000;          // supports decoded per chunk
  void visit(ConfigVisitor& v);
};

// Bilinear query of a feature map [1,C,h,w] at continuous pixel coordinates uv [N,2] of a W x H image
// (grid_sample, align_corners = false, coordinates clamped to +-(1 - 1e-6)): returns [N,C].
torch::Tensor query_features(const torch::Tensor& features, const torch::Tensor& uv, int64_t width, int64_t height);

struct ImplicitDecoderImpl : torch::nn::Module {
  ImplicitDecoderImpl(const DecoderOptions& options, int64_t dino_dim, int64_t cnn_dim);
  // Updates [N,14] for supports uv [N,2] of a W x H image, from one image's features (batch index 0). Supports
  // hidden under silhouettes (Supports::behind) read the features at their image position like any other.
  torch::Tensor forward(const torch::Tensor& uv, int64_t width, int64_t height, const EncoderFeatures& features);
  torch::Tensor decode_features(const torch::Tensor& f_dino, const torch::Tensor& f_cnn);  // [N,*] -> [N,14]
  torch::Tensor mlp_head(torch::Tensor fused);  // the MLP and the head on fused features [N,C] -> [N,14]
  torch::nn::Linear cnn_proj{nullptr}, gate{nullptr}, head{nullptr};
  torch::nn::ModuleList mlp{nullptr};
  int64_t dino_dim, cnn_dim, chunk;
};
TORCH_MODULE(ImplicitDecoder);

}  // namespace isplat

// DualEncoder: the DINO-style ViT branch and the CNN branch, each switchable for the ablations.
#pragma once
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include "encoder/features.h"
#include "encoder/vit.h"
#include "nets/cnn.h"

namespace isplat {

class ConfigVisitor;

struct EncoderOptions {
  bool dino = true;  // ablation: encoder.dino = false
  bool cnn = true;   // ablation: encoder.cnn = false
  ViTOptions vit;
  CNNOptions cnn_options;
  // Not a config key: false when the weights come from a trained checkpoint right after construction,
  // so start-up does not claim the ViT starts from random weights.
  bool initial_weights_matter = true;
  void visit(ConfigVisitor& v);
};

struct DualEncoderImpl : torch::nn::Module {
  explicit DualEncoderImpl(const EncoderOptions& options);
  // image [B,3,H,W] sRGB in [0,1]. The image is resized to the nearest multiple of 16 (at least one
  // patch); features cover the whole image either way. Smaller than one patch: Error.
  EncoderFeatures forward(const torch::Tensor& image);
  int64_t dino_dim() const;
  DinoViT vit{nullptr};
  CNNEncoder cnn{nullptr};
};
TORCH_MODULE(DualEncoder);

}  // namespace isplat

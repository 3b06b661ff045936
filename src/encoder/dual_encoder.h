// DualEncoder: the DINO-style ViT branch and the CNN branch, each switchable for the ablations.
#pragma once
#include <memory>
#include <string>

#include <torch/nn/module.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/pimpl.h>

#include "encoder/features.h"
#include "encoder/vit.h"
#include "nets/cnn.h"

namespace isplat {

class ConfigVisitor;
class FeatureNet;

struct EncoderOptions {
  bool dino = true;  // ablation: encoder.dino = false
  bool cnn = true;   // ablation: encoder.cnn = false
  // The semantic branch: vit (DINO-style, trained or from DINOv3 weights) | squeeze (frozen pretrained
  // SqueezeNet-1.1 ImageNet features and a trained 1x1 projection to the ViT's width, for when no DINO
  // checkpoint exists).
  std::string semantic = "vit";
  std::string semantic_backbone = "squeezenet1_1_features.safetensors";  // a file name: the weights lookup
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
  std::shared_ptr<const FeatureNet> squeeze;  // semantic = squeeze: frozen, not a parameter of this module
  torch::nn::Conv2d squeeze_proj{nullptr};    // semantic = squeeze: trained projection to encoder.vit's width
  CNNEncoder cnn{nullptr};
};
TORCH_MODULE(DualEncoder);

}  // namespace isplat

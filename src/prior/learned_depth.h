// The project's own monocular metric depth network, trained with `task: depth`: a U-Net from scratch, or a
// trained decoder on the frozen pretrained SqueezeNet-1.1 features (the weights lookup). Optionally focal-normalized:
// it predicts depth as a canonical camera would see it, scaled by the image's focal length, since metric scale from one
// image depends on the intrinsics.
#pragma once
#include <map>
#include <memory>
#include <string>

#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/pimpl.h>

namespace isplat {

class FeatureNet;

struct LearnedDepthOptions {
  std::string arch = "unet";      // unet (from scratch) | squeeze (frozen pretrained SqueezeNet-1.1 encoder)
  int64_t width = 32;             // decoder channel width
  bool focal_normalized = false;  // depth = canonical depth x (fx / W) / kCanonicalFocal
  std::string backbone = "squeezenet1_1_features.safetensors";  // squeeze: the pretrained features (weights lookup)
};

// fx / W of the canonical camera (a 60 degree horizontal field of view, as Hypersim's).
constexpr double kCanonicalFocal = 0.8660254037844386;

struct LearnedDepthNetImpl : torch::nn::Module {
  explicit LearnedDepthNetImpl(const LearnedDepthOptions& options);
  explicit LearnedDepthNetImpl(int64_t width = 32) : LearnedDepthNetImpl(LearnedDepthOptions{"unet", width}) {}
  // image [B,3,H,W] sRGB in [0,1]; K [B,3,3] (needed when focal-normalized, else ignored) -> metric
  // depth [B,1,H,W].
  torch::Tensor forward(const torch::Tensor& image, const torch::Tensor& K = torch::Tensor());
  torch::Tensor forward_log(const torch::Tensor& image, const torch::Tensor& K = torch::Tensor());  // log depth

  LearnedDepthOptions options;
  torch::nn::ModuleList down{nullptr}, up{nullptr}, lateral{nullptr};
  torch::nn::Conv2d stem{nullptr}, head{nullptr};
  std::shared_ptr<const FeatureNet> backbone;  // squeeze: frozen, not a parameter
};
TORCH_MODULE(LearnedDepthNet);

}  // namespace isplat

// The project's own monocular metric depth network, trained with `task: depth`: a U-Net from scratch, or a
// trained decoder on the pretrained SqueezeNet-1.1 features that ship in weights/ (frozen, or fine-tuned with
// tune_backbone()). Optionally focal-normalized: it predicts depth as a canonical camera would see it, scaled by the
// image's focal length, since metric scale from one image depends on the intrinsics.
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
  // squeeze arch: make the pretrained encoder's weights parameters of this net (under "backbone."), so training
  // fine-tunes them and the net's weights file carries them. Idempotent.
  void tune_backbone();
  bool backbone_tuned() const { return tuned_backbone_ != nullptr; }
  // The fine-tuned encoder's parameters (empty while it is frozen).
  std::vector<torch::Tensor> backbone_parameters() const;

  LearnedDepthOptions options;
  torch::nn::ModuleList down{nullptr}, up{nullptr}, lateral{nullptr};
  torch::nn::Conv2d stem{nullptr}, head{nullptr};
  std::shared_ptr<const FeatureNet> backbone;  // squeeze: frozen, not a parameter, unless tune_backbone()

 private:
  std::shared_ptr<torch::nn::Module> tuned_backbone_;  // holds the encoder's weights once tuned
};
TORCH_MODULE(LearnedDepthNet);

// Whether a weights map (a depth net's file, or a checkpoint's "prior/" tensors with that prefix) carries a
// fine-tuned encoder, so the net must call tune_backbone() before loading it.
bool has_tuned_backbone(const std::map<std::string, torch::Tensor>& tensors, const std::string& prefix = "");

}  // namespace isplat

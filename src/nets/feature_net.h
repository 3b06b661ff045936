// Frozen torchvision-layout feature networks (SqueezeNet 1.1, VGG16/19, AlexNet `features`), loaded from
// safetensors under torchvision's parameter names, with taps at chosen layers. Shared by the perceptual
// loss and LPIPS.
#pragma once
#include <map>
#include <string>
#include <vector>

#include <torch/types.h>

namespace isplat {

class FeatureNet {
 public:
  // `arch`: squeezenet1_1 | vgg16 | vgg19 | alexnet. `taps`: layer indices whose outputs are returned
  // (after that layer). Weights come from `path` (keys "<index>.weight" or "features.<index>.weight");
  // an empty path gives random weights, which callers must opt into explicitly.
  FeatureNet(const std::string& arch, std::vector<int> taps, const std::string& path);
  // x [B,3,H,W], already normalized as the network expects. Returns one map per tap.
  std::vector<torch::Tensor> forward(const torch::Tensor& x) const;
  std::vector<int64_t> tap_channels() const;
  const std::string& arch() const { return arch_; }
  bool pretrained() const { return pretrained_; }

  // Standard taps: LPIPS slices and the perceptual-loss layers (relu1_2, relu2_2, relu3_3, relu4_3 for VGG16).
  static std::vector<int> lpips_taps(const std::string& arch);
  static std::vector<int> perceptual_taps(const std::string& arch);

  // The layer list and weights, for graph export.
  struct Layer {
    enum Kind { Conv, Relu, MaxPool, Fire } kind;
    int64_t in = 0, out = 0, kernel = 0, stride = 1, pad = 0;
    bool ceil = false;
    int64_t squeeze = 0, e1 = 0, e3 = 0;  // Fire
  };
  const std::vector<Layer>& layers() const { return layers_; }
  const std::vector<int>& taps() const { return taps_; }
  const torch::Tensor& param(const std::string& name) const { return params_.at(name); }  // "<index>.weight", ...
  // Every weight by name. The tensors are the ones forward() reads, so an owner that fine-tunes them (the learned
  // depth prior) registers these handles as its own parameters.
  const std::map<std::string, torch::Tensor>& params() const { return params_; }

 private:
  std::string arch_;
  std::vector<Layer> layers_;
  std::vector<int> taps_;
  std::map<std::string, torch::Tensor> params_;  // "<index>.weight", "<index>.squeeze.weight", ...
  bool pretrained_ = false;
};

// Feature maps [B,C,H,W] scaled to unit length over channels (LPIPS; the perceptual loss does the same).
torch::Tensor normalize_channels(const torch::Tensor& features);

}  // namespace isplat

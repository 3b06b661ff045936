// Image quality metrics for evaluation and validation: masked PSNR, SSIM (Gaussian window sigma 1.5,
// 11x11, standard constants) and LPIPS v0.1 (squeeze / alex / vgg).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <torch/types.h>

#include "nets/feature_net.h"

namespace isplat {

// a, b [3,H,W] in [0,1]; mask [H,W] (nonzero = scored) or undefined for the whole image.
// Returns +inf for identical images, NaN when the mask is empty.
double psnr(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask = torch::Tensor());

// Mean SSIM over pixels whose 11x11 window lies inside the image and whose centre is in the mask
// (all such pixels when mask is undefined), averaged over channels. data_range 1.
double ssim(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask = torch::Tensor());
// The per-pixel SSIM map [H,W] (channel mean); border pixels without a full window are NaN.
torch::Tensor ssim_map(const torch::Tensor& a, const torch::Tensor& b);

// LPIPS v0.1: scaling layer, unit-normalized features, squared difference, linear 1x1 heads, spatial
// mean (over the mask, resized to each layer, when given), summed over layers.
class Lpips {
 public:
  // net: squeeze | alex | vgg. `backbone`: torchvision `features` safetensors; `heads`:
  // lpips_v0.1_<net>_lin.safetensors; "" = the weights lookup (core/weights.h).
  Lpips(const std::string& net, const std::string& backbone, const std::string& heads);
  double operator()(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask = torch::Tensor()) const;
  // The same in two steps, for many masks on one pair: the per-layer distance maps [1,1,h,w] (the networks run once),
  // then their mean over a mask. mean_distance(distance_maps(a, b), mask) == (*this)(a, b, mask).
  std::vector<torch::Tensor> distance_maps(const torch::Tensor& a, const torch::Tensor& b) const;
  static double mean_distance(const std::vector<torch::Tensor>& maps, const torch::Tensor& mask = torch::Tensor());
  const std::string& net() const { return net_; }

  // Finds the backbone and heads for `net` in a weights folder (e.g. weights); returns nullptr
  // and sets `why` when they are not there.
  static std::unique_ptr<Lpips> from_folder(const std::string& net, const std::string& folder, std::string& why);

 private:
  std::string net_;
  std::unique_ptr<FeatureNet> features_;
  std::vector<torch::Tensor> heads_;  // [1,C,1,1]
};

}  // namespace isplat

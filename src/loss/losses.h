// Training losses (DESIGN §3, paper): L1 and perceptual (+ Gram) on target renders, the scale-range hinge
// and the neighbour-smoothness regularizer on the Gaussians.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <torch/types.h>

#include "core/gaussians.h"
#include "nets/feature_net.h"

namespace isplat {

class ConfigVisitor;

struct LossOptions {
  double rgb = 1.0;         // L1 weight
  double perceptual = 1.0;  // perceptual (+ Gram) weight
  double reg = 0.1;         // weight of L_reg = scale * L_scale + smooth * L_smooth
  double scale = 0.1;
  double smooth = 0.1;
  double gram_gamma = 10.0;
  std::vector<double> scale_bounds = {-8.0, -3.0};  // bounds on log(scale / depth)
  int64_t knn = 8;
  std::string perceptual_net = "squeezenet1_1";                           // squeezenet1_1 | vgg16 | vgg19
  std::string perceptual_weights = "squeezenet1_1_features.safetensors";  // a file name: the weights lookup
  bool allow_random_perceptual = false;                                   // explicit opt-in to a random network
  // Depth task: l1_log weight, silog variance weight lambda (1 = scale-invariant shape term), and the
  // weight of |mean log error| (the global metric-scale term).
  double depth_l1 = 1.0, depth_lambda = 0.85, depth_scale = 0.0;
  double depth_sky = 0.0, depth_sky_m = 150.0;  // pixels without depth (sky) pushed beyond depth_sky_m
  void visit(ConfigVisitor& v);
};

// The perceptual term, averaged over taps: the squared distance of channel-normalized features
// phi per pixel, plus gamma * the mean squared Gram difference (x C), G = F F^T / (C H W).
class PerceptualLoss {
 public:
  // Logs loudly (naming the config key) and switches itself off when no weights are available.
  explicit PerceptualLoss(const LossOptions& options);
  bool enabled() const { return static_cast<bool>(net_); }
  std::string describe() const;
  // x, y [B,3,H,W] sRGB in [0,1].
  torch::Tensor operator()(const torch::Tensor& x, const torch::Tensor& y) const;

 private:
  std::unique_ptr<FeatureNet> net_;
  double gamma_;
};

torch::Tensor gram_matrix(const torch::Tensor& f);  // [B,C,H,W] -> [B,C,C] / (C H W)

// Hinge on log(scale / depth) outside [lo, hi]; scales [N,3], depth [N] (camera-space z of the means).
torch::Tensor scale_range_loss(const torch::Tensor& scales, const torch::Tensor& depth, double lo, double hi);
// Mean over i and its k neighbours of |log s_i - log s_j|_1 + |alpha_i - alpha_j|; neighbours [N,k].
torch::Tensor smoothness_loss(const torch::Tensor& scales, const torch::Tensor& opacities,
                              const torch::Tensor& neighbours);

}  // namespace isplat

// The training objectives: the weighted sum of the loss terms for the Gaussian model (DESIGN §3) and the
// log-depth losses of the learned depth prior. The trainer only calls these.
#pragma once
#include <map>
#include <memory>
#include <string>

#include <torch/types.h>

#include "core/gaussians.h"
#include "loss/losses.h"

namespace isplat {

using LossTerms = std::map<std::string, torch::Tensor>;

// One source view's prediction, rendered into its target views.
struct ObjectiveInput {
  torch::Tensor render;      // [T,3,H,W] sRGB in [0,1], the raw render
  torch::Tensor target;      // [T,3,H,W]
  torch::Tensor mask;        // [T,1,H,W], 1 = supervised
  Gaussians gaussians;       // any frame (scales and opacities are frame-free)
  torch::Tensor depth;       // [N] camera-space z of the means in the source view
  torch::Tensor support_uv;  // [N,2] source-image positions of the supports (for neighbours)
};

class GaussianObjective {
 public:
  explicit GaussianObjective(const LossOptions& options);
  std::string describe() const;  // e.g. "perceptual squeezenet1_1 (...)" or "perceptual off"
  // Unweighted terms l1, perceptual, scale, smooth for one view. Pixels outside the mask
  // take the target's value, so no term sees them.
  LossTerms terms(const ObjectiveInput& in) const;
  // Adds "total" = rgb*l1 + perceptual*perceptual + reg*(scale*scale + smooth*smooth) to `terms`.
  void add_total(LossTerms& terms) const;
  static LossTerms zero_terms();

 private:
  LossOptions options_;
  std::unique_ptr<PerceptualLoss> perceptual_;
};

// Depth prior on log depth, d = pred_log - log(depth) over valid pixels: l1_log = mean|d| (metric, per
// pixel), silog = sqrt(mean d^2 - lambda mean(d)^2) (lambda 1: shape only), scale = |mean d| (global
// metric scale), total = depth_l1 * l1_log + silog + depth_scale * scale. pred_log, depth, valid [B,H,W].
LossTerms depth_log_losses(const torch::Tensor& pred_log, const torch::Tensor& depth, const torch::Tensor& valid,
                           const LossOptions& options);

}  // namespace isplat

// Objective assembly: per-view terms and their weighted total.
#include "loss/objective.h"

#include <torch/torch.h>

#include "core/error.h"
#include "loss/knn.h"

namespace isplat {

GaussianObjective::GaussianObjective(const LossOptions& options) : options_(options) {
  if (options_.perceptual > 0) perceptual_ = std::make_unique<PerceptualLoss>(options_);
}

std::string GaussianObjective::describe() const {
  return perceptual_ ? perceptual_->describe() : std::string("off (weight 0)");
}

LossTerms GaussianObjective::zero_terms() {
  auto zero = torch::zeros({});
  return {{"l1", zero}, {"perceptual", zero}, {"scale", zero}, {"smooth", zero}};
}

LossTerms GaussianObjective::terms(const ObjectiveInput& in) const {
  const auto& o = options_;
  LossTerms t = zero_terms();
  const auto& mask = in.mask;
  t["l1"] = ((in.render - in.target).abs() * mask).sum() / (3.0 * mask.sum() + 1e-6);
  if (perceptual_ && perceptual_->enabled()) {
    const auto composite = in.render * mask + in.target * (1 - mask);
    t["perceptual"] = (*perceptual_)(composite, in.target);
  }
  t["scale"] = scale_range_loss(in.gaussians.scales, in.depth, o.scale_bounds.at(0), o.scale_bounds.at(1));
  if (o.smooth > 0)
    t["smooth"] = smoothness_loss(in.gaussians.scales, in.gaussians.opacities, knn_2d(in.support_uv, o.knn));
  return t;
}

void GaussianObjective::add_total(LossTerms& t) const {
  const auto& o = options_;
  t["total"] = o.rgb * t.at("l1") + o.perceptual * t.at("perceptual") +
               o.reg * (o.scale * t.at("scale") + o.smooth * t.at("smooth"));
}

LossTerms depth_log_losses(const torch::Tensor& pred_log, const torch::Tensor& depth, const torch::Tensor& valid,
                           const LossOptions& o) {
  auto v = valid > 0.5;
  const int64_t n = v.sum().item<int64_t>();
  ISPLAT_CHECK(n > 0, "depth training: a batch without valid depth");
  auto d = pred_log.masked_select(v) - torch::log(depth.masked_select(v));
  auto l1 = d.abs().mean();
  auto silog = torch::sqrt(torch::clamp_min((d * d).mean() - o.depth_lambda * d.mean().pow(2), 1e-12));
  auto scale = d.mean().abs();
  LossTerms t = {
      {"l1_log", l1}, {"silog", silog}, {"scale", scale}, {"total", o.depth_l1 * l1 + silog + o.depth_scale * scale}};
  if (o.depth_sky > 0) {
    // Pixels without depth are sky (or beyond a window): a hinge keeps their prediction beyond depth_sky_m,
    // so the prior can mark them as background instead of placing them at a wall's depth.
    const auto sky = ~v;
    t["sky"] = sky.any().item<bool>() ? torch::relu(std::log(o.depth_sky_m) - pred_log.masked_select(sky)).mean()
                                      : torch::zeros({}, pred_log.options());
    t["total"] = t["total"] + o.depth_sky * t["sky"];
  }
  return t;
}

}  // namespace isplat

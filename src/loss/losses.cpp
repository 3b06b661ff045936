// Loss terms and the perceptual network selection.
#include "loss/losses.h"

#include <torch/torch.h>

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/weights.h"
#include "nets/imagenet.h"

namespace isplat {

void LossOptions::visit(ConfigVisitor& v) {
  v.field("rgb", rgb, "weight of L1 on target renders (paper: 1)", Range::at_least(0));
  v.field("perceptual", perceptual, "weight of the perceptual + Gram term (paper: 1)", Range::at_least(0));
  v.field("reg", reg, "weight of L_reg = scale * L_scale + smooth * L_smooth (paper: 0.1)", Range::at_least(0));
  v.field("scale", scale, "weight of the scale-range hinge inside L_reg (paper: 0.1)", Range::at_least(0));
  v.field("smooth", smooth, "weight of neighbour smoothness inside L_reg (paper: 0.1)", Range::at_least(0));
  v.field("gram_gamma", gram_gamma, "weight of the Gram term inside the perceptual loss (paper: 10)",
          Range::at_least(0));
  v.field("scale_bounds", scale_bounds, "hinge bounds [lo, hi] on log(scale / depth) (paper: [-8, -3])");
  v.require("scale_bounds", scale_bounds.size() == 2 && scale_bounds[0] < scale_bounds[1],
            "must be two increasing numbers [lo, hi]");
  v.field("knn", knn, "neighbours per support for smoothness (paper: 8)", Range::at_least(1));
  v.field("perceptual_net", perceptual_net, "frozen perceptual network", {"squeezenet1_1", "vgg16", "vgg19"});
  v.field("perceptual_weights", perceptual_weights,
          "safetensors of the perceptual network under torchvision names: a file name is looked up ($"
          "INFINISPLAT_WEIGHTS, the checkout's weights/, ~/.cache/infinisplat/weights), a path is taken as given; "
          "missing = the term is off");
  v.field("depth_l1", depth_l1, "depth task: weight of the mean |log error| (metric, per pixel)", Range::at_least(0));
  v.field("depth_lambda", depth_lambda,
          "depth task: scale-invariant log loss lambda; 1 = pure shape (scale-free), 0 = plain log RMSE",
          Range::unit());
  v.field("depth_scale", depth_scale, "depth task: weight of |mean log error|, the global metric-scale term",
          Range::at_least(0));
  v.field("depth_sky", depth_sky,
          "depth task: weight of the sky term, a hinge on log depth that pushes pixels without depth (Hypersim: no "
          "geometry, i.e. sky and what windows show) beyond depth_sky_m; 0 = such pixels are not supervised",
          Range::at_least(0));
  v.field("depth_sky_m", depth_sky_m, "depth task: the sky term's depth in metres", Range::above(0));
  v.field("allow_random_perceptual", allow_random_perceptual,
          "run the perceptual term on a random network "
          "(only for experiments; never the default)");
}

PerceptualLoss::PerceptualLoss(const LossOptions& options) : gamma_(options.gram_gamma) {
  LossOptions o = options;
  const std::string configured = o.perceptual_weights;
  o.perceptual_weights = find_weights_file(configured);
  if (o.perceptual <= 0) return;
  const bool have = !o.perceptual_weights.empty() && std::filesystem::exists(o.perceptual_weights);
  if (!have && !o.allow_random_perceptual) {
    log_warn("**********************************************************************");
    log_warn("PERCEPTUAL LOSS IS OFF: no weights for ", o.perceptual_net, " (config key loss.perceptual_weights = '",
             configured, "': not found; ", missing_weights_hint(), ")");
    log_warn("**********************************************************************");
    return;
  }
  if (!have) log_warn("perceptual loss: using a RANDOM ", o.perceptual_net, " (loss.allow_random_perceptual = true)");
  net_ = std::make_unique<FeatureNet>(o.perceptual_net, FeatureNet::perceptual_taps(o.perceptual_net),
                                      have ? o.perceptual_weights : "");
}

std::string PerceptualLoss::describe() const {
  if (!net_) return "off";
  return net_->arch() + (net_->pretrained() ? " (pretrained)" : " (random)");
}

torch::Tensor gram_matrix(const torch::Tensor& f) {
  const int64_t B = f.size(0), C = f.size(1), HW = f.size(2) * f.size(3);
  auto x = f.reshape({B, C, HW});
  return torch::bmm(x, x.transpose(1, 2)) / static_cast<double>(C * HW);
}

torch::Tensor PerceptualLoss::operator()(const torch::Tensor& x, const torch::Tensor& y) const {
  ISPLAT_CHECK(net_, "perceptual loss is off");
  const auto fx = net_->forward(imagenet_normalize(x));
  std::vector<torch::Tensor> fy;
  {
    torch::NoGradGuard g;  // the target side needs no graph
    fy = net_->forward(imagenet_normalize(y));
  }
  // Features are unit-normalized over channels (as LPIPS does), so every layer contributes on the same
  // scale and the term is commensurate with L1 on [0,1] images.
  torch::Tensor total = torch::zeros({}, x.options());
  for (size_t l = 0; l < fx.size(); ++l) {
    const auto a = normalize_channels(fx[l]), b = normalize_channels(fy[l]);
    total = total + torch::mse_loss(a, b) * static_cast<double>(a.size(1));  // per-pixel squared distance
    if (gamma_ > 0)
      total = total + gamma_ * torch::mse_loss(gram_matrix(a), gram_matrix(b)) * static_cast<double>(a.size(1));
  }
  return total / static_cast<double>(fx.size());
}

torch::Tensor scale_range_loss(const torch::Tensor& scales, const torch::Tensor& depth, double lo, double hi) {
  auto r = torch::log(torch::clamp_min(scales, 1e-12)) - torch::log(torch::clamp_min(depth, 1e-6)).unsqueeze(1);
  return (torch::relu(lo - r) + torch::relu(r - hi)).mean();
}

torch::Tensor smoothness_loss(const torch::Tensor& scales, const torch::Tensor& opacities, const torch::Tensor& nb) {
  const int64_t N = scales.size(0), k = nb.size(1);
  auto log_s = torch::log(torch::clamp_min(scales, 1e-12));
  auto flat = nb.reshape({-1});
  auto ds = (log_s.unsqueeze(1) - log_s.index_select(0, flat).view({N, k, 3})).abs().sum(-1);
  auto da = (opacities.unsqueeze(1) - opacities.index_select(0, flat).view({N, k})).abs();
  return (ds + da).mean();
}

}  // namespace isplat

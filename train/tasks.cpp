// The two training tasks: Gaussians through the renderer, and the learned depth prior.
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "core/log.h"
#include "core/progress.h"
#include "geometry/camera_torch.h"
#include "geometry/color.h"
#include "io/safetensors.h"
#include "metrics/mask.h"
#include "model/infinisplat.h"
#include "prior/learned_depth.h"
#include "render/render.h"
#include "train/task.h"

namespace isplat {

bool all_finite(const torch::Tensor& t) {
  return torch::isfinite(t).all().item<bool>();
}

namespace {
using Clock = std::chrono::steady_clock;

class GaussianTask final : public TrainTask {
 public:
  explicit GaussianTask(const TrainConfig& config)
      : config_(config), pipeline_(config.model), objective_(config.loss) {}

  torch::nn::Module& module() override { return *pipeline_.model(); }
  std::string describe() const override {
    return cat("prior ", pipeline_.prior().describe(), "; perceptual loss ", objective_.describe());
  }

  LossTerms losses(const Batch& batch, int64_t first_sample, bool train, StepStats& stats,
                   std::vector<RenderedViews>* views) override {
    const int64_t B = batch.size(), T = batch.targets(), H = batch.target_image.size(3), W = batch.target_image.size(4);
    LossTerms acc = GaussianObjective::zero_terms();
    for (int64_t b = 0; b < B; ++b) {
      PriorInput in;
      in.image = batch.context_image[b];
      in.K = batch.context_K[b];
      in.depth = batch.context_depth[b];
      in.valid = batch.context_valid[b];
      in.seed = mix_seed(static_cast<uint64_t>(config_.runtime.seed), static_cast<uint64_t>(first_sample + b));
      Prediction p = pipeline_.run(in, batch.context_T[b], train);
      for (const auto& [k, v] : p.timings_ms) stats.timings_ms[k] += v;
      stats.supports += p.supports.count();
      // Diverged weights give non-finite Gaussians, which the renderer rejects: report the step as
      // non-finite so the loop skips it (and stops after train.max_bad_steps).
      const auto& gs = p.gaussians;
      if (!all_finite(gs.means) || !all_finite(gs.scales) || !all_finite(gs.quats) || !all_finite(gs.colors) ||
          !all_finite(gs.opacities)) {
        acc["total"] = torch::full({}, std::numeric_limits<float>::quiet_NaN());
        return acc;
      }

      auto t0 = Clock::now();
      const Camera cams{batch.target_K[b], batch.target_T[b], W, H};
      // No loss reads the normal map or the depth map.
      RenderOutput out = render(p.gaussians, cams, config_.render, RenderMaps::colour_only());
      stats.timings_ms["render_fwd"] += ms_since(t0);
      if (train) time_render_backward(out, p.gaussians, stats);
      t0 = Clock::now();
      auto rgb = torch::clamp(out.rgb, 0.0, 1.0);
      ObjectiveInput oi;
      oi.render = config_.model.composer.linear_rgb ? linear_to_srgb(rgb) : rgb;
      oi.target = batch.target_image[b];
      oi.mask = target_mask(batch, b, T, W, H);
      oi.gaussians = p.gaussians;
      oi.depth =
          transform_points(batch.context_T[b].to(p.gaussians.means.scalar_type()), p.gaussians.means).select(1, 2);
      oi.support_uv = p.supports.uv;
      if (views) views->push_back({oi.render.detach(), oi.mask.squeeze(1)});
      for (auto& [k, v] : objective_.terms(oi)) acc[k] = acc[k] + v;
      stats.timings_ms["losses"] += ms_since(t0);
    }
    for (auto& [k, v] : acc) v = v / static_cast<double>(B);
    objective_.add_total(acc);
    return acc;
  }

  void add_to_checkpoint(Checkpoint& ck) const override {
    // Carry the learned depth prior's weights, so the checkpoint alone predicts from a photo.
    if (const torch::nn::Module* prior_net = pipeline_.prior().embeddable_weights())
      put_module(ck, *prior_net, "prior/");
  }

 private:
  // [T,1,H,W]: the context's depth projected into each target (train.target_mask = projected), or all ones.
  torch::Tensor target_mask(const Batch& batch, int64_t b, int64_t T, int64_t W, int64_t H) const {
    if (config_.train.target_mask != "projected") return torch::ones({T, 1, H, W});
    const View src = to_view(Camera{batch.context_K[b], batch.context_T[b], W, H});
    std::vector<torch::Tensor> masks;
    for (int64_t t = 0; t < T; ++t)
      masks.push_back(projected_mask(batch.context_depth[b], batch.context_valid[b], src,
                                     to_view(Camera{batch.target_K[b][t], batch.target_T[b][t], W, H})));
    return torch::stack(masks).unsqueeze(1);
  }

  // The renderer's share of the backward pass, timed with gradient hooks on its output and its input.
  static void time_render_backward(RenderOutput& out, Gaussians& g, StepStats& stats) {
    auto* st = &stats;
    auto start = std::make_shared<Clock::time_point>();
    out.rgb.register_hook([start](torch::Tensor grad) {
      *start = Clock::now();
      return grad;
    });
    g.means.register_hook([start, st](torch::Tensor grad) {
      st->timings_ms["render_bwd"] += ms_since(*start);
      return grad;
    });
  }

  TrainConfig config_;
  Pipeline pipeline_;
  GaussianObjective objective_;
};

class DepthTask final : public TrainTask {
 public:
  explicit DepthTask(const TrainConfig& config) : net_(learned_depth_options(config.model.prior)), loss_(config.loss) {}

  torch::nn::Module& module() override { return *net_; }
  std::string describe() const override {
    return cat("learned depth prior (", net_->options.arch, net_->options.focal_normalized ? ", focal-normalized" : "",
               "; l1_log x ", loss_.depth_l1, " + silog lambda ", loss_.depth_lambda, " + scale x ", loss_.depth_scale,
               loss_.depth_sky > 0 ? cat(" + sky x ", loss_.depth_sky, " beyond ", loss_.depth_sky_m, " m") : "", ")");
  }

  LossTerms losses(const Batch& batch, int64_t, bool, StepStats&, std::vector<RenderedViews>*) override {
    const auto pred = net_->forward_log(batch.context_image, batch.context_K).squeeze(1);  // [B,H,W]
    return depth_log_losses(pred, batch.context_depth, batch.context_valid, loss_);
  }

  void finish(const std::string& run_dir) const override {
    // The prior's weights, under the net's own names.
    std::map<std::string, torch::Tensor> w;
    for (const auto& p : net_->named_parameters(true)) w[p.key()] = p.value().detach();
    write_safetensors((std::filesystem::path(run_dir) / "depth_net.safetensors").string(), w);
  }

 private:
  LearnedDepthNet net_;
  LossOptions loss_;
};
}  // namespace

std::unique_ptr<TrainTask> make_train_task(const TrainConfig& config) {
  if (config.task == "depth") return std::make_unique<DepthTask>(config);
  return std::make_unique<GaussianTask>(config);
}

}  // namespace isplat

// Model assembly with per-stage timings; ablations are switches on one code path.
#include "model/infinisplat.h"

#include <torch/torch.h>

#include <chrono>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/precision.h"
#include "core/progress.h"
#include "decoder/feature_sampler.h"

namespace isplat {

ModelOptions::ModelOptions() {
  // One support per pixel centre plus the silhouette supports: 0.5 px off the far side at near-side silhouettes,
  // with 3 pixels of hidden surface behind them, decoded by the dense head (lab/2026-12-06-lpips-gap: it holds the
  // photo better than area sampling, -0.013 to -0.017 LPIPS and +0.28 to +0.83 dB, with the same holes at wide
  // baselines); rotation updates in the surface's frame (lab/2026-11-26-surface-frame); no Gaussian narrower than
  // 0.35 source pixels, so views above the working size show fewer gaps (lab/2026-12-06-display-holes). The density
  // and the area keys are what sampler.mode = area (the paper's sampling) takes (lab/2026-11-28-seeds).
  sampler.mode = "pixel";
  sampler.budget_mode = "per_pixel";
  sampler.density = 0.85;
  sampler.edge_shift = 0.5;
  sampler.edge_behind = 3;
  decoder.mode = "dense";
  composer.orientation = "surface";
  composer.scale_floor_px = 0.35;
}

void ModelOptions::visit(ConfigVisitor& v) {
  v.field("variant", variant, "rgb (monocular prior) or lidar (sparse-prompt prior); recorded in checkpoints",
          {"rgb", "lidar"});
  v.section("prior", "the frozen depth prior", prior);
  v.section("sampler", "geometry-guided support sampling", sampler);
  v.section("encoder", "the dual-branch encoder", encoder);
  v.section("decoder", "the decoder of bounded Gaussian updates", decoder);
  v.section("composer", "bounded Gaussian updates", composer);
}

InfiniSplatImpl::InfiniSplatImpl(const ModelOptions& o) : options(o) {
  encoder = register_module("encoder", DualEncoder(o.encoder));
  const int64_t dd = encoder->dino_dim(), cd = o.encoder.cnn ? o.encoder.cnn_options.out_channels : 0;
  if (o.decoder.mode == "implicit") decoder = register_module("decoder", ImplicitDecoder(o.decoder, dd, cd));
  if (o.decoder.mode == "dense") dense = register_module("dense", DenseHead(dd, cd));
  if (o.decoder.mode == "dense" && o.sampler.mode != "pixel")
    log_warn("decoder.mode = dense predicts per pixel; it was trained and measured with sampler.mode = pixel");
}

Prediction InfiniSplatImpl::forward(const torch::Tensor& image, const torch::Tensor& K, const torch::Tensor& T_cw,
                                    const torch::Tensor& depth, const torch::Tensor& valid, uint64_t seed) {
  ISPLAT_CHECK(image.dim() == 3 && image.size(0) == 3, "model: image must be [3, H, W], got ", image.sizes());
  const int64_t H = image.size(1), W = image.size(2);
  ISPLAT_CHECK(depth.dim() == 2 && depth.size(0) == H && depth.size(1) == W, "model: depth ", depth.sizes(),
               " must match the image ", H, "x", W);
  Prediction p;
  auto t0 = std::chrono::steady_clock::now();
  p.supports =
      sample_supports(depth, valid, K, image, options.sampler, seed, options.composer.orientation == "surface");
  p.base = make_base_gaussians(p.supports);
  p.timings_ms["sampler"] = ms_since(t0);
  const int64_t N = p.supports.count();
  if (options.decoder.mode == "none") {
    p.delta = torch::zeros({N, kDeltaDim});
  } else {
    // runtime.precision = bf16: the networks' matmuls and convolutions in bf16; what leaves them is fp32 again.
    const bool bf16 = compute_precision() == Precision::bf16;
    auto fp32 = [](const torch::Tensor& t) { return t.defined() ? t.to(torch::kFloat32) : t; };
    t0 = std::chrono::steady_clock::now();
    EncoderFeatures f;
    {
      const Bf16Region region(bf16);
      f = encoder->forward(image.unsqueeze(0));
    }
    f = {fp32(f.dino), fp32(f.cnn)};
    p.timings_ms["encoder"] = ms_since(t0);
    t0 = std::chrono::steady_clock::now();
    {
      const Bf16Region region(bf16);
      p.delta = fp32(decode(f, p.supports.uv, W, H));
    }
    p.timings_ms["decoder"] = ms_since(t0);
  }
  t0 = std::chrono::steady_clock::now();
  p.gaussians = compose(p.base, p.delta, K.to(torch::kFloat32), T_cw.to(torch::kFloat32), options.composer);
  p.timings_ms["composer"] = ms_since(t0);
  return p;
}

torch::Tensor InfiniSplatImpl::decode(const EncoderFeatures& f, const torch::Tensor& uv, int64_t width,
                                      int64_t height) {
  ISPLAT_CHECK(decoder || dense, "model: decoder.mode = none has no learned decoder");
  return decoder ? decoder->forward(uv, width, height, f)
                 : sample_features(dense->forward(f, width, height).to(torch::kFloat32), uv, width, height);
}

Prediction InfiniSplatImpl::predict(const torch::Tensor& image, const torch::Tensor& K, const torch::Tensor& T_cw,
                                    const torch::Tensor& depth, const torch::Tensor& valid, uint64_t seed) {
  torch::NoGradGuard no_grad;
  const bool was_training = is_training();
  eval();
  Prediction p = forward(image, K, T_cw, depth, valid, seed);
  if (was_training) train();
  return p;
}

Pipeline::Pipeline(const ModelOptions& options, const std::map<std::string, torch::Tensor>* embedded_prior)
    : prior_(make_depth_prior(options.prior, embedded_prior)), model_(options) {}

Prediction Pipeline::run(const PriorInput& input, const torch::Tensor& T_cw, bool train,
                         const std::function<void(PriorOutput&)>& after_prior) {
  auto t0 = std::chrono::steady_clock::now();
  PriorOutput prior = prior_->predict(input);
  if (after_prior) after_prior(prior);
  const double prior_ms = ms_since(t0);
  Prediction p = train ? model_->forward(input.image, prior.K, T_cw, prior.depth, prior.valid, input.seed)
                       : model_->predict(input.image, prior.K, T_cw, prior.depth, prior.valid, input.seed);
  p.timings_ms["prior"] = prior_ms;
  return p;
}

}  // namespace isplat

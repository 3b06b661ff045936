// prior.type = sparse (the "LiDAR" variant): sparse depth prompts align a monocular prior (align_prompts.cpp).
#include <torch/torch.h>

#include <random>

#include "core/error.h"
#include "data/perturb.h"
#include "geometry/camera_torch.h"
#include "prior/prior_common.h"

namespace isplat {
namespace priors {

namespace {

class SparsePrior final : public DepthPrior {
 public:
  explicit SparsePrior(const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded) : o_(o) {
    ISPLAT_CHECK(o.sparse.finest <= o.sparse.bandwidth, "prior.sparse.finest (", o.sparse.finest,
                 ") must not exceed prior.sparse.bandwidth (", o.sparse.bandwidth, ")");
    // Below 1e-3 the range kernel's 1/(2 range^2) overflows to inf and 0 * inf poisons the fit with NaN.
    ISPLAT_CHECK(o.sparse.depth_range == 0 || o.sparse.depth_range >= 1e-3, "prior.sparse.depth_range (",
                 o.sparse.depth_range, ") must be 0 (off) or at least 0.001");
    if (o.sparse.densify == "image") return;  // the prompts alone: no monocular prior to load
    if (o.sparse.mono == "learned") {
      mono_ = make_learned_prior(o, embedded);
    } else if (o.sparse.mono == "torchscript") {
      mono_ = make_torchscript_prior(o);
    }
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    torch::Tensor prompts = in.prompts;
    if (!prompts.defined()) {
      ISPLAT_CHECK(in.depth.defined(), "prior.type = sparse needs prompts or the frame's depth to draw them from");
      prompts = draw_prompts(in.depth, in.valid.defined() ? in.valid : (in.depth > 0), o_.sparse.prompts,
                             o_.sparse.noise, in.seed);
    }
    SparsePriorOptions so = o_.sparse;
    torch::Tensor mono = monocular(in);
    if (so.densify == "blend" && !mono.defined()) so.densify = "image";  // mono = none: nothing to blend in
    if (so.densify == "fit" && !mono.defined()) mono = torch::ones({in.image.size(1), in.image.size(2)});
    const SparseDensity d = densify_prompts(in.image, mono, prompts, so);
    PriorOutput out = finish(d.depth, intrinsics_for(in, o_.hfov_deg));
    out.confidence = d.confidence;
    return out;
  }
  std::string describe() const override {
    const std::string mono = mono_                         ? mono_->describe()
                             : o_.sparse.mono == "dataset" ? cat("the true depth warped by ", o_.sparse.mono_warp)
                                                           : std::string("a constant");
    return cat("sparse prompts (", o_.sparse.prompts, ", noise ", o_.sparse.noise, ", residual field ",
               o_.sparse.bandwidth, " -> ", o_.sparse.finest, o_.sparse.cross_validate ? " cross-validated" : "",
               "), densify ", o_.sparse.densify, o_.sparse.densify == "image" ? "" : " with " + mono, ", far ",
               o_.sparse.far, " beyond ", o_.sparse.far_spacings, " spacings");
  }
  const torch::nn::Module* embeddable_weights() const override { return mono_ ? mono_->embeddable_weights() : nullptr; }

 private:
  // The monocular depth to align, or undefined (mono = none, or densify = image).
  torch::Tensor monocular(const PriorInput& in) const {
    if (o_.sparse.densify == "image") return {};
    if (mono_) return mono_->predict(in).depth;
    if (o_.sparse.mono != "dataset") return {};
    const torch::Tensor& truth = in.reference_depth.defined() ? in.reference_depth : in.depth;
    ISPLAT_CHECK(truth.defined(), "prior.sparse.mono = dataset needs the frame's depth (an evaluation with depth)");
    auto z = truth.to(torch::kFloat32);
    auto ok = torch::isfinite(z) & (z > 0);
    ISPLAT_CHECK(ok.any().item<bool>(), "prior.sparse.mono = dataset: the frame's depth has no valid pixel");
    z = torch::where(ok, z, z.masked_select(ok).max());  // no depth (sky): as far as the farthest surface
    if (o_.sparse.mono_warp <= 0) return z;
    PerturbOptions warp;
    warp.depth_warp = o_.sparse.mono_warp;
    return perturb_depth(z, torch::ones_like(z), warp, in.seed ^ 0x3A5C0FFEEull).depth;
  }
  PriorOptions o_;
  std::unique_ptr<DepthPrior> mono_;
};

}  // namespace

std::unique_ptr<DepthPrior> make_sparse_prior(const PriorOptions& o,
                                              const std::map<std::string, torch::Tensor>* embedded) {
  return std::make_unique<SparsePrior>(o, embedded);
}

}  // namespace priors

torch::Tensor draw_prompts(const torch::Tensor& depth, const torch::Tensor& valid, int64_t count, double noise,
                           uint64_t seed) {
  auto d = depth.to(torch::kFloat32).contiguous();
  auto ok = usable_depth(d, valid).contiguous();
  auto idx = torch::nonzero(ok.flatten()).squeeze(1);
  ISPLAT_CHECK(idx.numel() > 0, "sparse prior: the source depth has no valid pixel to draw prompts from");
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 12345);
  std::normal_distribution<double> eps(0.0, 1.0);
  const int64_t W = d.size(1), n = std::min<int64_t>(count, idx.numel());
  auto out = torch::empty({n, 3});
  const int64_t* ip = idx.data_ptr<int64_t>();
  const float* dp = d.data_ptr<float>();
  float* op = out.data_ptr<float>();
  // Partial Fisher-Yates: n distinct pixels.
  std::vector<int64_t> pool(ip, ip + idx.numel());
  for (int64_t k = 0; k < n; ++k) {
    const int64_t r = k + static_cast<int64_t>(rng() % static_cast<uint64_t>(pool.size() - k));
    std::swap(pool[k], pool[r]);
    const int64_t p = pool[k];
    op[3 * k] = static_cast<float>(p % W + 0.5);
    op[3 * k + 1] = static_cast<float>(p / W + 0.5);
    op[3 * k + 2] = static_cast<float>(dp[p] * std::max(0.05, 1.0 + noise * eps(rng)));
  }
  return out;
}

}  // namespace isplat

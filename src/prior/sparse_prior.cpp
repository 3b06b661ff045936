// prior.type = sparse (the "LiDAR" variant): sparse depth prompts align a monocular prior (align_prompts.cpp).
#include <torch/torch.h>

#include <random>

#include "core/error.h"
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
    ISPLAT_CHECK(prompts.dim() == 2 && prompts.size(1) == 3 && prompts.size(0) >= 3,
                 "sparse prior: prompts must be [P>=3, 3] (u, v, z), got ", prompts.sizes());
    const int64_t H = in.image.size(1), W = in.image.size(2);
    torch::Tensor mono = mono_ ? mono_->predict(in).depth : torch::ones({H, W});
    return finish(align_to_prompts(mono, prompts, o_.sparse), intrinsics_for(in, o_.hfov_deg));
  }
  std::string describe() const override {
    return cat("sparse prompts (", o_.sparse.prompts, ", noise ", o_.sparse.noise, ", residual field ",
               o_.sparse.bandwidth, " -> ", o_.sparse.finest, o_.sparse.cross_validate ? " cross-validated" : "",
               ") aligning ", mono_ ? mono_->describe() : std::string("a constant"));
  }
  const torch::nn::Module* embeddable_weights() const override { return mono_ ? mono_->embeddable_weights() : nullptr; }

 private:
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

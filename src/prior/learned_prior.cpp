// prior.type = learned: the project's own monocular depth net (prior/learned_depth.h), optionally flip-averaged.
#include <torch/torch.h>

#include "core/error.h"
#include "core/log.h"
#include "geometry/camera_torch.h"
#include "io/checkpoint.h"
#include "io/safetensors.h"
#include "prior/learned_depth.h"
#include "prior/prior_common.h"

namespace isplat {
namespace priors {

namespace {

class LearnedPrior final : public DepthPrior {
 public:
  explicit LearnedPrior(const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded = nullptr)
      : o_(o), net_(learned_depth_options(o)) {
    const auto load = [&](const std::map<std::string, torch::Tensor>& tensors, const std::string& prefix,
                          const std::string& what) { load_named_tensors(*net_, tensors, prefix, what); };
    if (embedded && embedded->count("prior/stem.weight")) {
      load(*embedded, "prior/", "checkpoint: embedded depth-net weights do not fit the net");
      source_ = "weights embedded in the checkpoint";
    } else if (o.learned_weights.empty()) {
      log_warn(
          "depth prior: the learned depth net has no weights (prior.learned_weights is empty); its depth is "
          "untrained. Train it with a `task: depth` config or pass prior.torchscript.");
    } else {
      load(read_safetensors(o.learned_weights).tensors, "",
           o.learned_weights + ": does not fit the learned depth net (prior.learned_width must match)");
      source_ = o.learned_weights;
    }
    net_->eval();
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    const torch::Tensor K = intrinsics_for(in, o_.hfov_deg);
    const torch::Tensor image = in.image.to(torch::kFloat32).unsqueeze(0), K1 = K.to(torch::kFloat32).unsqueeze(0);
    torch::Tensor log_d = net_->forward_log(image, K1);
    if (o_.learned_flip_average) {
      // The mirrored photo is another view of the same scene. Averaging in log depth keeps the result metric and
      // cancels errors the net makes differently on the two.
      const torch::Tensor Km = mirror_K(K1, image.size(3));
      log_d = 0.5 * (log_d + net_->forward_log(image.flip({3}), Km).flip({3}));
    }
    torch::Tensor d = torch::exp(log_d)[0][0];
    if (o_.learned_sky_m > 0) d = torch::where(d >= o_.learned_sky_m, torch::zeros_like(d), d);  // sky: invalid
    return finish_monocular(d, K, o_, in);
  }
  std::string describe() const override {
    const std::string kind = cat("learned depth net (", o_.learned_arch, o_.learned_focal ? ", focal-normalized" : "",
                                 o_.learned_flip_average ? ", flip-averaged" : "");
    return source_.empty() ? kind + ", untrained)" : kind + ", " + source_ + ")";
  }
  const torch::nn::Module* embeddable_weights() const override { return source_.empty() ? nullptr : net_.get(); }

 private:
  PriorOptions o_;
  LearnedDepthNet net_;
  std::string source_;
};

}  // namespace

std::unique_ptr<DepthPrior> make_learned_prior(const PriorOptions& o,
                                               const std::map<std::string, torch::Tensor>* embedded) {
  return std::make_unique<LearnedPrior>(o, embedded);
}

}  // namespace priors
}  // namespace isplat

// prior.type = dataset: the tuple's own depth (the oracle).
#include <torch/torch.h>

#include "core/error.h"
#include "prior/prior_common.h"

namespace isplat {
namespace priors {

namespace {

class DatasetPrior final : public DepthPrior {
 public:
  explicit DatasetPrior(const PriorOptions& o) : o_(o) {}
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    ISPLAT_CHECK(in.depth.defined(),
                 "prior.type = dataset needs the frame's depth, and this input has none; use "
                 "prior.type = learned | torchscript | sparse");
    auto d = in.depth.to(torch::kFloat32);
    if (in.valid.defined()) d = torch::where(in.valid > 0, d, torch::zeros_like(d));
    return finish(d, intrinsics_for(in, o_.hfov_deg));
  }
  std::string describe() const override { return "dataset depth (oracle)"; }

 private:
  PriorOptions o_;
};

}  // namespace

std::unique_ptr<DepthPrior> make_dataset_prior(const PriorOptions& o) {
  return std::make_unique<DatasetPrior>(o);
}

}  // namespace priors
}  // namespace isplat

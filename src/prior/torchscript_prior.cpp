// prior.type = torchscript: a user's traced depth model, input [1,3,H,W] in [0,1], output metric depth.
#include <torch/script.h>
#include <torch/torch.h>

#include <filesystem>

#include "core/error.h"
#include "core/weights.h"
#include "prior/prior_common.h"

namespace isplat {
namespace priors {

namespace {

class TorchScriptPrior final : public DepthPrior {
 public:
  explicit TorchScriptPrior(const PriorOptions& o) : o_(o) {
    ISPLAT_CHECK(!o.torchscript.empty(), "prior.type = torchscript needs prior.torchscript (path of a traced model)");
    // A bare file name is looked up like the other weights (core/weights.h); a path is taken as given.
    o_.torchscript = find_weights_file(o.torchscript);
    ISPLAT_CHECK(!o_.torchscript.empty() && std::filesystem::exists(o_.torchscript), o.torchscript,
                 ": no such file (prior.torchscript; a file name is looked up: ", missing_weights_hint(),
                 ", though that command fetches no depth model)");
    try {
      module_ = torch::jit::load(o_.torchscript);
    } catch (const std::exception& e) {
      fail(o_.torchscript, ": cannot load TorchScript model: ", e.what());
    }
    module_.eval();
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    const int64_t H = in.image.size(1), W = in.image.size(2);
    torch::jit::IValue out;
    try {
      out = module_.forward({in.image.unsqueeze(0).to(torch::kFloat32)});
    } catch (const std::exception& e) {
      fail(o_.torchscript, ": the depth model failed on a [1,3,", H, ",", W, "] input: ", e.what());
    }
    ISPLAT_CHECK(out.isTensor(), o_.torchscript, ": the depth model must return one tensor (metric depth [1,1,H,W])");
    auto d = out.toTensor();
    // Contract: [1,1,H,W]; [1,H,W] and [H,W] are accepted as the same thing.
    if (d.dim() == 4 && d.size(0) == 1 && d.size(1) == 1)
      d = d[0][0];
    else if (d.dim() == 3 && d.size(0) == 1)
      d = d[0];
    if (d.dim() != 2 || d.size(0) != H || d.size(1) != W)
      fail(o_.torchscript, ": depth model returned shape ", out.toTensor().sizes(), ", expected [1, 1, ", H, ", ", W,
           "] (metric depth at the input size)");
    return finish_monocular(d, intrinsics_for(in, o_.hfov_deg), o_, in);
  }
  std::string describe() const override { return "TorchScript depth model (" + o_.torchscript + ")"; }

 private:
  PriorOptions o_;
  torch::jit::Module module_;
};

}  // namespace

std::unique_ptr<DepthPrior> make_torchscript_prior(const PriorOptions& o) {
  return std::make_unique<TorchScriptPrior>(o);
}

}  // namespace priors
}  // namespace isplat

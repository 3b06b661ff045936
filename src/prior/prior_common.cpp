// The finishing steps the depth priors share: intrinsics, validity, and the monocular priors' metric scale.
#include "prior/prior_common.h"

#include <torch/torch.h>

#include "core/error.h"

namespace isplat {
namespace priors {

torch::Tensor intrinsics_for(const PriorInput& in, double hfov) {
  return in.K.defined() ? in.K.to(torch::kFloat32) : estimate_K(in.image.size(2), in.image.size(1), hfov);
}

void check_image(const PriorInput& in) {
  ISPLAT_CHECK(in.image.defined() && in.image.dim() == 3 && in.image.size(0) == 3,
               "depth prior: image must be [3, H, W], got ",
               in.image.defined() ? in.image.sizes() : torch::IntArrayRef{});
}

PriorOutput finish(torch::Tensor depth, torch::Tensor K) {
  depth = depth.to(torch::kFloat32);
  auto valid = (torch::isfinite(depth) & (depth > 0)).to(torch::kFloat32);
  return {torch::where(valid > 0, depth, torch::zeros_like(depth)), K, valid};
}

namespace {

// The median of reference / depth over the pixels valid in both; 0 when none is.
double reference_ratio(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& reference,
                       const torch::Tensor& reference_valid) {
  auto ref = reference.to(torch::kFloat32);
  auto both = (valid > 0) & torch::isfinite(ref) & (ref > 0);
  if (reference_valid.defined()) both = both & (reference_valid > 0);
  if (!both.any().item<bool>()) return 0.0;
  return (ref.masked_select(both) / depth.masked_select(both)).median().item<double>();
}

}  // namespace

PriorOutput finish_monocular(torch::Tensor depth, torch::Tensor K, const PriorOptions& o, const PriorInput& in) {
  PriorOutput out = finish(std::move(depth), std::move(K));
  double scale = 0.0;
  if (o.camera_height_m > 0) {
    scale = floor_height_scale(out.depth, out.valid, out.K, o.camera_height_m);
    out.floor_scaled = scale > 0;
  } else if (o.reference_scale) {
    ISPLAT_CHECK(in.depth.defined(),
                 "prior.reference_scale needs the frame's own depth, and this input has none (it is a diagnostic for "
                 "datasets with depth)");
    scale = reference_ratio(out.depth, out.valid, in.depth, in.valid);
  }
  if (scale > 0) out.depth = out.depth * static_cast<float>(scale);
  return out;
}

}  // namespace priors
}  // namespace isplat

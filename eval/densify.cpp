// AbsRel and delta < 1.25 of densified depth on the pixels without prompts and on the pixels a perturbation removed.
#include "eval/densify.h"

#include <torch/torch.h>

#include "core/error.h"
#include "eval/depth_eval.h"

namespace isplat {

namespace {
DensifyScore score_on(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& where) {
  const DepthErrors e = depth_errors(pred, depth, where.to(torch::kFloat32));
  DensifyScore s;
  s.pixels = e.pixels;
  if (e.pixels > 0) s.abs_rel = e.abs_rel_sum / double(e.pixels), s.delta1 = e.delta1_count / double(e.pixels);
  return s;
}
}  // namespace

DensifyScores score_densification(const torch::Tensor& densified, const torch::Tensor& prompt_pixels,
                                  const torch::Tensor& true_depth, const torch::Tensor& true_valid,
                                  const torch::Tensor& seen_valid) {
  ISPLAT_CHECK(densified.dim() == 2 && densified.sizes() == true_depth.sizes() &&
                   true_valid.sizes() == true_depth.sizes() && seen_valid.sizes() == true_depth.sizes(),
               "densification scores: densified ", densified.sizes(), ", true depth ", true_depth.sizes(), ", valid ",
               true_valid.sizes(), " and seen valid ", seen_valid.sizes(), " must all be [H,W] of one size");
  const int64_t H = true_depth.size(0), W = true_depth.size(1);
  const auto truth = (true_valid > 0).logical_and(true_depth > 0).logical_and(torch::isfinite(true_depth));
  auto prompted = torch::zeros({H * W}, torch::kBool);
  if (prompt_pixels.defined() && prompt_pixels.numel() > 0) {
    const auto c = prompt_pixels.select(1, 0), r = prompt_pixels.select(1, 1);
    const auto inside = (c >= 0) & (c < W) & (r >= 0) & (r < H);
    prompted.index_fill_(0, (r * W + c).index({inside}), true);
  }
  const auto pred = densified.to(torch::kFloat32), depth = torch::nan_to_num(true_depth.to(torch::kFloat32), 0, 0, 0);
  DensifyScores out;
  out.unprompted = score_on(pred, depth, truth.logical_and(prompted.view({H, W}).logical_not()));
  out.removed = score_on(pred, depth, truth.logical_and(seen_valid <= 0));
  return out;
}

}  // namespace isplat

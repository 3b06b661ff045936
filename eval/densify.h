// Densification measured directly: a sparse prior's densified depth against the true source depth, on the pixels that
// held no prompt and on the pixels whose depth a perturbation removed (issue 75 item 3).
#pragma once
#include <torch/types.h>

#include "eval/report.h"

namespace isplat {

struct DensifyScores {
  DensifyScore unprompted, removed;
};

// densified [H,W] (0 where the prior left no depth); prompt_pixels [P,2] (col, row) of the prompts it had;
// true_depth/true_valid [H,W] the unperturbed source depth; seen_valid [H,W] the valid mask the method saw (after
// the source perturbation). Unprompted: true-valid pixels without a prompt; removed: true-valid pixels the perturbation
// made invalid. Both score only where the densified depth is positive; a set without such a pixel has pixels 0.
DensifyScores score_densification(const torch::Tensor& densified, const torch::Tensor& prompt_pixels,
                                  const torch::Tensor& true_depth, const torch::Tensor& true_valid,
                                  const torch::Tensor& seen_valid);

}  // namespace isplat

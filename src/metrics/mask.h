// The evaluation (and training) mask: source depth projected into the target view, closed
// morphologically. It depends only on the data, so every method is scored on the same pixels.
#pragma once
#include <torch/types.h>

#include "geometry/camera.h"

namespace isplat {

// depth/valid [H,W] of the source; returns a [Ht,Wt] float 0/1 mask of target pixels that see
// source-visible surface. Each source pixel splats its projected footprint; then a closing of `radius`.
torch::Tensor projected_mask(const torch::Tensor& depth, const torch::Tensor& valid, const View& source,
                             const View& target, int radius = 2);

}  // namespace isplat

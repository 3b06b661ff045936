// Filling small holes in a depth map before sampling, so missing depth still gets supports with the photo's colours.
#pragma once
#include <cstdint>

#include <torch/types.h>

namespace isplat {

struct FilledDepth {
  torch::Tensor depth;  // [H,W] float metres, 0 where still invalid
  torch::Tensor valid;  // [H,W] float 0/1
  int64_t filled = 0;   // pixels that became valid
};

// Every unusable pixel (mask off, or depth NaN/inf/<= 0) within max_px pixels (Chebyshev) of a usable one gets
// depth from a push-pull pyramid in log depth: holes take a smooth blend of the depth around them (always between
// its smallest and largest value), coarse where the hole is wide. Usable pixels keep their depth (as float32);
// pixels farther than max_px (the inside of large missing regions) stay invalid. depth, valid [H,W] on the CPU;
// max_px >= 0 (0 = no filling: unusable depth only becomes 0 and invalid). Deterministic, no gradient.
FilledDepth fill_depth_holes(const torch::Tensor& depth, const torch::Tensor& valid, int64_t max_px);

}  // namespace isplat

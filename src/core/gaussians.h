// The Gaussian set: the plain struct passed from the composer to the renderer, the PLY writer and losses.
#pragma once
#include <ATen/TensorIndexing.h>
#include <torch/types.h>

namespace isplat {

// Activated values (DESIGN §2). Unbatched: means [N,3], scales [N,3] (metres), quats [N,4] (w,x,y,z,
// unnormalized), colors [N,3] (linear RGB in [0,1]), opacities [N]. Batched: a leading [B] on each.
struct Gaussians {
  torch::Tensor means;
  torch::Tensor scales;
  torch::Tensor quats;
  torch::Tensor colors;
  torch::Tensor opacities;

  bool batched() const { return means.dim() == 3; }
  int64_t count() const { return means.size(batched() ? 1 : 0); }
  int64_t batch() const { return batched() ? means.size(0) : 0; }
  Gaussians select(int64_t b) const {  // one set from a batch
    return {means[b], scales[b], quats[b], colors[b], opacities[b]};
  }
  Gaussians index(const torch::Tensor& keep) const {  // subset of an unbatched set (bool mask or indices)
    return {means.index({keep}), scales.index({keep}), quats.index({keep}), colors.index({keep}),
            opacities.index({keep})};
  }
  Gaussians to(torch::Dtype dtype) const {
    return {means.to(dtype), scales.to(dtype), quats.to(dtype), colors.to(dtype), opacities.to(dtype)};
  }
  Gaussians detach() const {
    return {means.detach(), scales.detach(), quats.detach(), colors.detach(), opacities.detach()};
  }
};

}  // namespace isplat

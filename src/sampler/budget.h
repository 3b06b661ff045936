// Internal to the sampler: budgets (how many supports the options ask for) and the hole fill applied first.
#pragma once
#include <cstdint>
#include <vector>

#include "sampler/depth_fill.h"
#include "sampler/grid.h"

namespace isplat {
namespace sampling {

// The options once fill_px has been applied.
SamplerOptions without_fill(SamplerOptions o);

// sampler/depth_fill's push-pull fill at the options' fill_px.
FilledDepth fill_holes(const torch::Tensor& depth, const torch::Tensor& valid, const SamplerOptions& o);

// Per-pixel detail weights in [floor, 1] (0 where depth is unusable), see SamplerOptions.
std::vector<float> detail_weights(const Grid& g, const SamplerOptions& o);

// budget_mode "detail": density times the weights' sum, within [min_budget, max_budget].
int64_t detail_budget(const SamplerOptions& o, const std::vector<float>& weight);

}  // namespace sampling
}  // namespace isplat

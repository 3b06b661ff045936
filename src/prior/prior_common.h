// Internal to the depth priors: the checks and finishing steps every prior shares, and one constructor per prior
// for the factory (make_depth_prior in depth_prior.cpp).
#pragma once
#include <map>
#include <memory>
#include <string>

#include "prior/depth_prior.h"

namespace isplat {
namespace priors {

// The input's K, or one estimated from the field of view.
torch::Tensor intrinsics_for(const PriorInput& in, double hfov);

void check_image(const PriorInput& in);

// Float depth with invalid (non-finite, <= 0) pixels set to 0 and masked.
PriorOutput finish(torch::Tensor depth, torch::Tensor K);

// Monocular priors: metric scale from the camera's height when asked and a floor is visible, or (a diagnostic)
// from the frame's own depth.
PriorOutput finish_monocular(torch::Tensor depth, torch::Tensor K, const PriorOptions& o, const PriorInput& in);

std::unique_ptr<DepthPrior> make_dataset_prior(const PriorOptions& o);  // dataset_prior.cpp
std::unique_ptr<DepthPrior> make_learned_prior(
    const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded);  // learned_prior.cpp
std::unique_ptr<DepthPrior> make_torchscript_prior(const PriorOptions& o);         // torchscript_prior.cpp
std::unique_ptr<DepthPrior> make_sparse_prior(
    const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded);  // sparse_prior.cpp

}  // namespace priors
}  // namespace isplat

// Internal to the sparse prior: a field over the image fitted to values at sparse prompts, coarse to fine with
// Gaussian kernels, optionally joint bilateral on a guide (log depth or image colour) and cross-validated.
#pragma once
#include <torch/types.h>

#include <cstdint>
#include <functional>
#include <vector>

#include "prior/depth_prior.h"

namespace isplat {
namespace priors {

// What a prompt's weight also depends on: the gap between the guide at the prompt and at the query point,
// exp(-|gap|^2 / (2 range^2)). channels 0 or range 0: the kernel is spatial only.
struct PromptGuide {
  int channels = 0;
  double range = 0;
  std::vector<double> at_prompts;                         // [P * channels]
  std::function<void(double u, double v, double* g)> at;  // the guide at a point of a level's grid
  const std::vector<double>* pixels = nullptr;            // [H * W * channels], the guide at pixel centres
  bool on() const { return channels > 0 && range > 0; }
};

struct PromptField {
  torch::Tensor field;          // [H,W] the sum of the levels used
  int64_t levels = 0;           // levels used
  std::vector<double> heldout;  // [P] each prompt's value predicted without its fold (when asked), else empty
};

// prompts [P,3] (u, v, z) as a row-major float array; values [P] the quantity to spread. Levels use the kernel
// widths `sigmas` (pixels, coarse to fine), each fitting what the coarser left at the prompts. With cross_validate,
// the level count is the one whose held-out error (5 folds, a fixed shuffle) is least; with want_heldout, the
// held-out predictions at that count are returned. Deterministic.
PromptField fit_prompt_field(const float* prompts, int64_t P, int64_t H, int64_t W, const std::vector<double>& values,
                             const PromptGuide& guide, const std::vector<double>& sigmas, bool cross_validate,
                             bool want_heldout);

// The global step of align_to_prompts: mono depth [H,W] mapped by the least-squares scale and shift in inverse depth
// that fit the prompts [P,3] (one trimming pass). `shaped` (optional): false when the map degenerated to a constant
// (a flat or inverted prior).
torch::Tensor align_global(const torch::Tensor& mono_depth, const torch::Tensor& prompts, bool* shaped);

// The alignment of align_to_prompts (align_prompts.cpp), with each prompt's cross-validated log depth: the
// residual field refitted without the prompt's fold (the global scale/shift keeps every prompt).
struct AlignedPrompts {
  torch::Tensor depth;              // [H,W]
  int64_t levels = 0;               // residual field levels used
  std::vector<double> heldout_log;  // [P] when asked
};
AlignedPrompts align_with_heldout(const torch::Tensor& mono_depth, const torch::Tensor& prompts,
                                  const SparsePriorOptions& options, bool want_heldout);

}  // namespace priors
}  // namespace isplat

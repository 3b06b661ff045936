// AdamW whose step reads and writes each parameter and its two moments once (LibTorch's step makes about ten passes),
// with LibTorch's options, state and checkpoint format.
#pragma once
#include <torch/optim/adamw.h>

namespace isplat {

// A drop-in torch::optim::AdamW: same options per group (learning rate, betas, eps, weight decay), same state per
// parameter (step, exp_avg, exp_avg_sq), so save() and load() read and write the same archives. Contiguous float
// parameters without amsgrad take the fused loop, everything else LibTorch's own tensor operations. The loop rounds
// as LibTorch's vectorized kernels do on x86 with FMA (bit for bit on the session machines; the tests allow rounding).
class FusedAdamW : public torch::optim::AdamW {
 public:
  using torch::optim::AdamW::AdamW;
  torch::Tensor step(LossClosure closure = nullptr) override;
  // How many parameters the last step updated in the fused loop (the rest took LibTorch's operations).
  int64_t fused_in_last_step() const { return fused_in_last_step_; }

 private:
  int64_t fused_in_last_step_ = 0;
};

}  // namespace isplat

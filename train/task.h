// Training tasks: what the trainer optimizes and how a batch becomes loss terms. The Gaussian task trains
// the InfiniSplat model through the renderer; the depth task trains the learned depth prior. The loop,
// checkpoints, logs and validation stay in the trainer.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <torch/nn/module.h>
#include <torch/types.h>

#include "data/tuples.h"
#include "io/checkpoint.h"
#include "loss/objective.h"
#include "train/train_config.h"

namespace isplat {

// True when every element of t is finite (one reduction, one sync).
bool all_finite(const torch::Tensor& t);

struct StepStats {
  std::map<std::string, double> losses;  // total, l1, perceptual, scale, smooth (or depth terms)
  std::map<std::string, double>
      timings_ms;  // data, prior, sampler, encoder, decoder, composer, render_fwd, losses, backward, render_bwd, optim
  double lr = 0;
  double step_ms = 0;  // the whole step, wall clock
  int64_t supports = 0;
  bool skipped = false;
};

// One batch element's target views as the model rendered them (validation panels and PSNR).
struct RenderedViews {
  torch::Tensor render;  // [T,3,H,W] sRGB in [0,1], raw (nothing pasted in from the target)
  torch::Tensor mask;    // [T,H,W], 1 = scored
};

// Weights trained at lr_scale x the scheduled learning rate (e.g. a fine-tuned pretrained encoder at 0.1).
struct ParamGroup {
  std::vector<torch::Tensor> params;
  double lr_scale = 1.0;
};

class TrainTask {
 public:
  virtual ~TrainTask() = default;
  virtual torch::nn::Module& module() = 0;  // the trainable weights
  // How the optimizer splits module()'s parameters; every parameter in exactly one group.
  virtual std::vector<ParamGroup> param_groups() { return {{module().parameters(), 1.0}}; }
  virtual std::string describe() const = 0;
  // Loss terms including "total" (NaN when the prediction is non-finite) for a batch whose first tuple has
  // the global index `first_sample` (it seeds prompt draws); adds timings and support counts to `stats`.
  // With `views`, also returns each element's renders.
  virtual LossTerms losses(const Batch& batch, int64_t first_sample, bool train, StepStats& stats,
                           std::vector<RenderedViews>* views) = 0;
  virtual void add_to_checkpoint(Checkpoint& ck) const {}   // e.g. the embedded depth prior
  virtual void finish(const std::string& run_dir) const {}  // e.g. the depth net's own weights file
};

std::unique_ptr<TrainTask> make_train_task(const TrainConfig& config);  // by config.task

}  // namespace isplat

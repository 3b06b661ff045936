// The config-driven trainer: data -> prior -> model -> renderer -> losses -> AdamW, with validation
// renders, JSON-lines logs, atomic checkpoints, bit-exact resume and a clean Ctrl-C.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <torch/optim/adamw.h>

#include "data/loader.h"
#include "loss/losses.h"
#include "model/infinisplat.h"
#include "prior/learned_depth.h"
#include "train/train_config.h"

namespace isplat {

struct StepStats {
  std::map<std::string, double> losses;  // total, l1, perceptual, scale, smooth (or depth terms)
  std::map<std::string, double>
      timings_ms;  // data, prior, sampler, encoder, decoder, composer, render_fwd, losses, backward, render_bwd, optim
  double lr = 0;
  int64_t supports = 0;
  bool skipped = false;
};

class Trainer {
 public:
  explicit Trainer(const TrainConfig& config);
  ~Trainer();

  // Loads model, optimizer, step and RNG state. "auto" picks <out>/checkpoints/last.safetensors if present.
  void resume(const std::string& path);
  // Trains to config.train.steps. Returns 0, or 130 when stopped by Ctrl-C (after saving a checkpoint).
  int run();

  StepStats train_step();                                                // one optimizer step on the next batch
  double validate(bool write_images);                                    // mean validation loss (also logs PSNR)
  void save(const std::string& path, bool with_optimizer = true) const;  // atomic
  int64_t step() const { return step_; }
  torch::nn::Module& trainable();
  const torch::nn::Module& trainable() const;

  static void request_stop();  // async-signal-safe: the loop saves and exits at the next step boundary

 private:
  std::map<std::string, torch::Tensor> gaussian_losses(const Batch& batch, StepStats& stats, bool train,
                                                       std::vector<torch::Tensor>* predictions = nullptr);
  std::map<std::string, torch::Tensor> depth_losses(const Batch& batch);
  void write_log(const StepStats& s);
  void write_val_images(const Batch& batch, const std::vector<torch::Tensor>& predictions, int64_t index);
  void checkpoint(bool periodic);

  TrainConfig config_;
  std::unique_ptr<Pipeline> pipeline_;  // task gaussians
  LearnedDepthNet depth_net_{nullptr};  // task depth
  std::unique_ptr<PerceptualLoss> perceptual_;
  std::unique_ptr<TupleSampler> train_sampler_, val_sampler_;
  std::unique_ptr<BatchLoader> loader_;
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  int64_t step_ = 0;
  int64_t bad_steps_ = 0;
  double best_val_ = std::numeric_limits<double>::infinity();
  std::string run_dir_, log_path_;
};

}  // namespace isplat

// The config-driven trainer: data -> prior -> model -> renderer -> losses -> AdamW, with validation
// renders, JSON-lines logs, atomic checkpoints, bit-exact resume and a clean Ctrl-C.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <torch/optim/adamw.h>

#include "core/precision.h"
#include "data/loader.h"
#include "io/checkpoint.h"
#include "io/folder_lock.h"
#include "io/jsonl.h"
#include "train/data_parallel.h"
#include "train/task.h"
#include "train/train_config.h"

namespace isplat {

// The sequences of one split under data.hypersim.root and every data.extra_roots folder, in that order.
std::vector<Sequence> read_training_sequences(const DataOptions& data, const std::string& split);

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
  // Where gradients of all ranks are averaged before clipping (data-parallel training); one rank: nothing.
  void synchronize_gradients(StepStats& s);
  bool writer() const;  // rank 0 (or the only process): the one that writes logs, images and checkpoints
  void write_log(const StepStats& s);
  void write_curves() const;  // <run>/curves.png, refreshed at each validation
  void write_val_images(const Batch& batch, const RenderedViews& views, int64_t index);
  Checkpoint make_checkpoint(bool with_optimizer) const;

  TrainConfig config_;
  // runtime.precision, applied by each step and validation itself: an experiment trains rows of different
  // precisions in one process, whose own runtime section is not theirs.
  Precision precision_;
  std::unique_ptr<TrainTask> task_;
  std::unique_ptr<TupleSampler> train_sampler_, val_sampler_;
  std::unique_ptr<BatchLoader> loader_;
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  std::vector<double> lr_scales_;  // per optimizer parameter group
  int64_t step_ = 0;
  int64_t bad_steps_ = 0;
  double best_val_ = std::numeric_limits<double>::infinity();
  std::string run_dir_;
  double cpu_offset_ = 0, cpu_start_ = 0;  // process CPU seconds: before this process (resume) and at start
  double cpu_seconds() const;              // CPU time spent on this run so far, across resumes
  std::unique_ptr<JsonlWriter> log_;
  std::unique_ptr<DataParallel> dp_;  // null for one process
  bool stop_ = false;                 // a stop request, agreed by all ranks
  CheckpointFolder checkpoints_;
  std::unique_ptr<FolderLock> lock_;  // one trainer per run folder
};

}  // namespace isplat

// The training configuration: data, model, losses, renderer, optimizer and the loop, as one typed schema.
#pragma once
#include <string>
#include <vector>

#include "core/runtime.h"
#include "data/hypersim.h"
#include "data/perturb.h"
#include "data/tuples.h"
#include "loss/losses.h"
#include "model/infinisplat.h"
#include "render/render.h"
#include "train/data_parallel.h"

namespace isplat {

class ConfigVisitor;

struct DataOptions {
  HypersimOptions hypersim;
  std::vector<std::string> extra_roots;  // more release folders, read like hypersim.root
  TupleOptions tuples;
  std::string val_split = "val";
  int64_t batch_size = 1;
  int64_t workers = 2;
  int64_t prefetch = 4;
  int64_t val_tuples = 8;
  void visit(ConfigVisitor& v);
};

struct OptimOptions {
  double lr = 5e-5;  // paper
  double weight_decay = 0.01;
  double beta1 = 0.9, beta2 = 0.999;
  int64_t warmup = 100;       // linear warm-up steps, then cosine decay
  double min_lr_ratio = 0.1;  // cosine floor as a fraction of lr
  double grad_clip = 1.0;     // global gradient-norm clip; 0 = off
  void visit(ConfigVisitor& v);
};

struct LoopOptions {
  std::string out = "out/train";
  int64_t steps = 1000;
  int64_t log_every = 1;
  int64_t val_every = 200;
  int64_t checkpoint_every = 200;
  int64_t keep_last = 3;
  int64_t max_bad_steps = 5;
  int64_t stop_at = 0;  // end this sitting after this step (checkpointed; --resume auto continues); 0 = off
  std::string target_mask = "projected";  // projected | none
  int64_t val_images = 3;
  void visit(ConfigVisitor& v);
};

struct TrainConfig {
  RuntimeOptions runtime;
  std::string task = "gaussians";  // gaussians | depth
  DataOptions data;
  ModelOptions model;
  LossOptions loss;
  RenderOptions render;
  OptimOptions optim;
  LoopOptions train;
  DistOptions dist;
  void visit(ConfigVisitor& v);
};

// Learning rate at `step`: linear warm-up to lr, then cosine down to lr * min_lr_ratio at `total`.
double scheduled_lr(const OptimOptions& o, int64_t step, int64_t total);

}  // namespace isplat

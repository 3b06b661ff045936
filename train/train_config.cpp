// Training config schema.
#include "train/train_config.h"

#include <cmath>

#include "core/config.h"

namespace isplat {

void DataOptions::visit(ConfigVisitor& v) {
  v.section("hypersim", "the training set, in the Hypersim release layout", hypersim);
  v.field("extra_roots", extra_roots,
          "more folders in the Hypersim release layout, each with its own metadata CSVs, read with the same split, "
          "colour and scene lists as hypersim.root and trained on together (e.g. the real release plus generated "
          "scenes). hypersim.scenes and hypersim.scene_blacklist apply to every folder, and generated scene names "
          "repeat across folders");
  v.section("tuples", "context/target tuples", tuples);
  v.field("val_split", val_split, "split used for validation renders", {"train", "val", "test", "all"});
  v.field("batch_size", batch_size, "tuples per optimizer step", Range::at_least(1));
  v.field("workers", workers, "loader threads (0 = load in the training thread)", Range::at_least(0));
  v.field("prefetch", prefetch, "batches kept ready ahead of the step", Range::at_least(1));
  v.field("val_tuples", val_tuples, "validation tuples scored at each validation", Range::at_least(1));
}

void OptimOptions::visit(ConfigVisitor& v) {
  v.field("lr", lr, "AdamW peak learning rate (paper: 5e-5)", Range::above(0));
  v.field("weight_decay", weight_decay, "AdamW decoupled weight decay", Range::at_least(0));
  v.field("beta1", beta1, "AdamW beta1", Range::between(0, 1));
  v.field("beta2", beta2, "AdamW beta2", Range::between(0, 1));
  v.field("warmup", warmup, "linear warm-up steps", Range::at_least(0));
  v.field("min_lr_ratio", min_lr_ratio, "cosine decay floor, as a fraction of lr", Range::unit());
  v.field("grad_clip", grad_clip, "clip the global gradient norm to this (0 = off)", Range::at_least(0));
}

void LoopOptions::visit(ConfigVisitor& v) {
  v.field("out", out, "run folder: checkpoints, logs and validation renders go here");
  v.field("steps", steps, "optimizer steps", Range::at_least(1));
  v.field("log_every", log_every, "steps between JSON-lines log records", Range::at_least(1));
  v.field("val_every", val_every, "steps between validations (and best-checkpoint updates)", Range::at_least(1));
  v.field("checkpoint_every", checkpoint_every, "steps between checkpoints", Range::at_least(1));
  v.field("keep_last", keep_last, "periodic checkpoints kept (plus best and last)", Range::at_least(1));
  v.field("max_bad_steps", max_bad_steps, "consecutive non-finite steps before training stops", Range::at_least(1));
  v.field("stop_at", stop_at,
          "end this sitting after this step with a checkpoint, keeping the schedule of train.steps "
          "(--resume auto continues); 0 = run to the end",
          Range::at_least(0));
  v.field("target_mask", target_mask, "score target pixels that see the context's surface, or all pixels",
          {"projected", "none"});
  v.field("val_images", val_images, "validation tuples saved as PNG panels", Range::at_least(0));
}

void TrainConfig::visit(ConfigVisitor& v) {
  v.section("runtime", "threads, seed and logging", runtime);
  v.field("task", task, "what to train: the Gaussian model, or the learned depth prior", {"gaussians", "depth"});
  v.section("data", "training data", data);
  v.section("model", "the InfiniSplat model", model);
  v.section("loss", "loss terms and weights", loss);
  v.section("render", "the splatting renderer", render);
  v.section("optim", "optimizer and schedule", optim);
  v.section("train", "the training loop", train);
  v.section("dist", "data-parallel training over c10d/Gloo (PyTorch's RANK, WORLD_SIZE, MASTER_ADDR, MASTER_PORT)",
            dist);
}

double scheduled_lr(const OptimOptions& o, int64_t step, int64_t total) {
  if (o.warmup > 0 && step < o.warmup) return o.lr * (step + 1) / static_cast<double>(o.warmup);
  const double span = std::max<int64_t>(1, total - o.warmup);
  const double t = std::min(1.0, (step - o.warmup) / span);
  return o.lr * (o.min_lr_ratio + (1 - o.min_lr_ratio) * 0.5 * (1 + std::cos(M_PI * t)));
}

}  // namespace isplat

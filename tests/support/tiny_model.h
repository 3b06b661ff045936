// Tiny model and training configurations for tests: the real code paths at toy sizes.
#pragma once
#include <string>

#include "data/synth/generate.h"
#include "model/infinisplat.h"
#include "train/train_config.h"

namespace isplat::test {

// ViT 32-d with `vit_depth` blocks and 2 heads, CNN width 4, the paper's area sampling (with the lab's edge supports)
// at a fixed budget of `budget` supports and its implicit decoder, MLP [32, 16]; otherwise the model's defaults.
ModelOptions tiny_model_options(int64_t budget = 600, int64_t vit_depth = 1);
// The model's defaults (a support per pixel and behind silhouettes, the dense head) with the same tiny encoder.
ModelOptions tiny_default_options(int64_t vit_depth = 1);

// Trains `model` (tiny_model_options(1500) unless given) on a tiny generated dataset at 48x32 with 2 targets, dataset
// depth, no perceptual term and no loader threads.
TrainConfig tiny_train_config(const GenerateOptions& data, const std::string& out, int64_t steps,
                              const ModelOptions& model = tiny_model_options(1500));

}  // namespace isplat::test

// Tiny generated datasets for tests: a few low-resolution frames in every layout, made in well under a second.
#pragma once
#include <string>
#include <vector>

#include "data/synth/generate.h"
#include "eval/datasets.h"

namespace isplat::test {

// Options for a small dataset: 1 train (tilt-shift) + 1 val scene of `frames` frames at 64x48, and one
// scene per evaluation layout; callers may adjust before generating.
GenerateOptions tiny_dataset_options(const std::string& out, int frames = 8);
// Options for training scenes only: `scenes` train scenes cycling through `styles`, no val, test or evaluation
// scenes, no tilt-shift camera.
GenerateOptions style_dataset_options(const std::string& out, int frames, const std::vector<std::string>& styles,
                                      int scenes);
// Options for evaluation sets only (e.g. {"courtyard_colmap"}): no train or val scenes, one scene per set.
GenerateOptions eval_dataset_options(const std::string& out, int frames, const std::vector<std::string>& datasets);
// Generates into a fresh temp folder and returns GenerateOptions used (options.out is the folder).
GenerateOptions make_tiny_dataset(const std::string& tag, int frames = 8);
// The generated courtyard (COLMAP layout) of `g` as an evaluation dataset named "courtyard".
EvalDatasetOptions tiny_courtyard_set(const GenerateOptions& g);

}  // namespace isplat::test

// Tiny generated datasets for tests.
#include "support/tiny_dataset.h"

#include "core/log.h"
#include "support/test_util.h"

namespace isplat::test {

GenerateOptions tiny_dataset_options(const std::string& out, int frames) {
  GenerateOptions o;
  o.out = out;
  o.seed = 3;
  o.train_scenes = 1;
  o.val_scenes = 1;
  o.test_scenes = 0;
  o.frames = frames;
  o.width = 64;
  o.height = 48;
  o.supersample = 1;
  o.tilt_shift_every = 2;  // the second scene (val) uses a tilt-shift camera
  o.eval_scenes = 1;
  o.eval_frames = frames;
  o.eval_width = 64;
  o.eval_height = 48;
  return o;
}

GenerateOptions style_dataset_options(const std::string& out, int frames, const std::vector<std::string>& styles,
                                      int scenes) {
  GenerateOptions o = tiny_dataset_options(out, frames);
  o.train_scenes = scenes;
  o.val_scenes = 0;
  o.test_scenes = 0;
  o.tilt_shift_every = 0;
  o.train_styles = styles;
  o.eval_datasets = {};
  return o;
}

GenerateOptions eval_dataset_options(const std::string& out, int frames, const std::vector<std::string>& datasets) {
  GenerateOptions o = tiny_dataset_options(out, frames);
  o.train_scenes = 0;
  o.val_scenes = 0;
  o.eval_datasets = datasets;
  return o;
}

GenerateOptions make_tiny_dataset(const std::string& tag, int frames) {
  GenerateOptions o = tiny_dataset_options(temp_dir(tag), frames);
  QuietLogs quiet;
  generate_datasets(o);
  return o;
}

EvalDatasetOptions tiny_courtyard_set(const GenerateOptions& g) {
  EvalDatasetOptions d;
  d.name = "courtyard";
  d.format = "colmap";
  d.root = generated_eval_root(g.out, "courtyard_colmap");
  return d;
}

}  // namespace isplat::test

// Tiny model and training configurations for tests.
#include "support/tiny_model.h"

#include "model/model_io.h"

namespace isplat::test {

ModelOptions tiny_model_options(int64_t budget, int64_t vit_depth) {
  ModelOptions o;
  o.encoder.vit.size = "custom";
  o.encoder.vit.embed_dim = 32;
  o.encoder.vit.depth = vit_depth;
  o.encoder.vit.heads = 2;
  o.encoder.cnn_options.width = 4;
  // The paper's layout with the lab's edge supports (config_version 2's sampler, the implicit decoder) at a size the
  // test chooses; the model's defaults otherwise. The default layout's own tests set theirs.
  o.sampler = model_defaults(2).sampler;
  o.sampler.budget_mode = "fixed";
  o.sampler.budget = budget;
  o.decoder.mode = "implicit";
  o.decoder.hidden = {32, 16};
  return o;
}

ModelOptions tiny_default_options(int64_t vit_depth) {
  ModelOptions o;
  o.encoder = tiny_model_options(600, vit_depth).encoder;
  return o;
}

TrainConfig tiny_train_config(const GenerateOptions& data, const std::string& out, int64_t steps,
                              const ModelOptions& model) {
  TrainConfig c;
  c.runtime.seed = 3;
  c.data.hypersim.root = generated_hypersim_root(data.out);
  c.data.tuples.width = 48;
  c.data.tuples.height = 32;
  c.data.tuples.targets = 2;
  c.data.tuples.window = 4;
  c.data.workers = 0;
  c.data.val_tuples = 2;
  c.model = model;
  c.model.prior.type = "dataset";
  c.loss.perceptual = 0;  // keeps tests fast; the perceptual term has its own tests
  c.optim.lr = 3e-3;
  c.optim.warmup = 2;
  c.train.out = out;
  c.train.steps = steps;
  c.train.val_every = 1000;
  c.train.checkpoint_every = 1000;
  c.train.val_images = 0;
  return c;
}

}  // namespace isplat::test

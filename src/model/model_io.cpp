// Checkpoint -> ModelOptions -> Pipeline with loaded weights.
#include "model/model_io.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/retired_keys.h"

namespace isplat {

int config_version(const Checkpoint& ck, const std::string& source) {
  const auto it = ck.metadata.find("config_version");
  if (it == ck.metadata.end()) return 1;
  const auto v = parse_int(it->second);
  if (!v || *v < 1 || *v > kModelConfigVersion)
    fail(source, ": config_version '", it->second, "' is not one this build knows (1..", kModelConfigVersion,
         "); a newer build wrote it");
  return static_cast<int>(*v);
}

ModelOptions model_defaults(int config_version) {
  ModelOptions o;
  // Stored configs written before these keys existed ran without them: the prior aligned (fit), no scale floor. A
  // config that has a key keeps its value (every config written since stores every key).
  o.prior.sparse.densify = "fit";
  o.composer.scale_floor_px = 0.0;
  if (config_version >= 3) return o;
  // Version 2: the paper's area sampling with the lab's edge supports, per-pixel share and floor, and its implicit
  // decoder (the defaults from 2026-12-06 to 2026-12-07).
  o.sampler.mode = "area";
  o.sampler.edge_supports = true;
  o.sampler.image_share = 0.5;
  o.sampler.pixel_floor = 1.0;
  o.sampler.edge_band = 2;
  o.decoder.mode = "implicit";
  if (config_version >= 2) return o;
  // Version 1: the paper release's fixed budget, no edge supports, rotations in the camera frame.
  o.sampler.budget_mode = "fixed";
  o.sampler.budget = 100000;
  o.sampler.density = 1.0;
  o.sampler.edge_supports = false;
  o.sampler.image_share = 0.0;
  o.sampler.pixel_floor = 0.0;
  o.sampler.edge_behind = 0;
  o.sampler.edge_shift = 0.0;
  o.sampler.edge_band = 0;
  o.composer.orientation = "camera";
  return o;
}

ModelOptions model_options_from_checkpoint(const Checkpoint& ck, const std::string& source,
                                           const std::vector<std::string>& overrides) {
  const nlohmann::json config = parse_json(ck.config_json(), source + " (stored config)");
  if (!config.is_object() || !config.contains("model")) fail(source, ": stored config has no 'model' section");
  ConfigDocument doc;
  doc.json = config["model"];
  doc.origin[""] = source + " (stored config)";
  strip_retired_keys(doc.json, source + " (stored config)");  // options retired since it was written
  apply_overrides(doc, overrides);                            // the --set machinery, on the model section
  ModelOptions options = model_defaults(config_version(ck, source));
  apply_config(doc, options);
  return options;
}

std::unique_ptr<Pipeline> load_pipeline(const std::string& path, const std::vector<std::string>& overrides) {
  return load_pipeline(load_checkpoint(path), path, overrides);
}

namespace {
// A stored config that does not describe the stored weights would otherwise build a model of any size
// (4.8 GB, 93 s) before the shape check names the mismatch: compare the ViT, the largest part, first.
void check_model_size(const Checkpoint& ck, const ModelOptions& options, const std::string& path) {
  if (!options.encoder.dino || options.encoder.semantic != "vit") return;
  double stored = 0;
  for (const auto& [name, t] : ck.tensors)
    if (name.rfind("model/", 0) == 0) stored += static_cast<double>(t.numel());
  const double dim = static_cast<double>(options.encoder.vit.dim());
  const double vit = 12.0 * dim * dim * static_cast<double>(options.encoder.vit.blocks());  // qkv, proj, MLP
  if (vit > 1.5 * stored + 1e6)
    fail(path, ": the stored config describes a ViT of about ", static_cast<int64_t>(vit / 1e6),
         "M parameters (encoder.vit: width ", options.encoder.vit.dim(), ", ", options.encoder.vit.blocks(),
         " blocks) but the checkpoint holds ", static_cast<int64_t>(stored / 1e6),
         "M model parameters in all; the config does not match the weights");
}
}  // namespace

std::unique_ptr<Pipeline> load_pipeline(const Checkpoint& ck, const std::string& path,
                                        const std::vector<std::string>& overrides) {
  ErrorContext context("building the model of the checkpoint ", path);
  ModelOptions options = model_options_from_checkpoint(ck, path, overrides);
  check_model_size(ck, options, path);
  options.encoder.vit.weights.clear();  // the checkpoint already holds the ViT weights
  options.encoder.initial_weights_matter = false;
  // An explicit prior.learned_weights override names the prior the caller wants (e.g. a decoder scored with
  // another prior's depth); otherwise the checkpoint's embedded prior keeps it self-contained.
  const bool prior_overridden = std::any_of(overrides.begin(), overrides.end(), [](const std::string& o) {
    return o.rfind("prior.learned_weights=", 0) == 0;
  });
  if (prior_overridden && ck.tensors.count("prior/stem.weight"))
    log_info("model: prior.learned_weights=", options.prior.learned_weights,
             " replaces the depth-net weights embedded in ", path);
  auto pipeline = std::make_unique<Pipeline>(options, prior_overridden ? nullptr : &ck.tensors);
  load_module(ck, *pipeline->model(), path);
  // NaN weights predict nothing: the scene would be written with 0 Gaussians and exit 0.
  for (const auto& p : pipeline->model()->named_parameters(true))
    if (!torch::isfinite(p.value()).all().item<bool>())
      fail(path, ": weight 'model/", p.key(), "' holds NaN or infinite values; the checkpoint is damaged");
  pipeline->model()->eval();
  log_info("model: trained weights (encoder, decoder) from ", path, " (step ", ck.step(), ", variant ", options.variant,
           ", prior: ", pipeline->prior().describe(), ")");
  return pipeline;
}

}  // namespace isplat

// Checkpoint -> ModelOptions -> Pipeline with loaded weights.
#include "model/model_io.h"

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"

namespace isplat {

ModelOptions model_options_from_checkpoint(const Checkpoint& ck, const std::string& source,
                                           const std::vector<std::string>& overrides) {
  nlohmann::json config;
  try {
    config = nlohmann::json::parse(ck.config_json());
  } catch (const nlohmann::json::parse_error& e) {
    fail(source, ": stored config is not valid JSON: ", e.what());
  }
  if (!config.contains("model")) fail(source, ": stored config has no 'model' section");
  ConfigDocument doc;
  doc.json = config["model"];
  doc.origin[""] = source + " (stored config)";
  apply_overrides(doc, overrides);  // the --set machinery, on the model section
  ModelOptions options;
  apply_config(doc, options);
  return options;
}

std::unique_ptr<Pipeline> load_pipeline(const std::string& path, const std::vector<std::string>& overrides) {
  return load_pipeline(load_checkpoint(path), path, overrides);
}

std::unique_ptr<Pipeline> load_pipeline(const Checkpoint& ck, const std::string& path,
                                        const std::vector<std::string>& overrides) {
  ModelOptions options = model_options_from_checkpoint(ck, path, overrides);
  options.encoder.vit.weights.clear();  // the checkpoint already holds the ViT weights
  options.encoder.initial_weights_matter = false;
  auto pipeline = std::make_unique<Pipeline>(options, &ck.tensors);
  load_module(ck, *pipeline->model(), path);
  pipeline->model()->eval();
  log_info("model: trained weights (encoder, decoder) from ", path, " (step ", ck.step(), ", variant ", options.variant,
           ", prior: ", pipeline->prior().describe(), ")");
  return pipeline;
}

}  // namespace isplat

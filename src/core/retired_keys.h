// Config keys retired after their studies (issue 70): the behaviour each kept, so stored configs still load.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace isplat {

struct RetiredKey {
  RetiredKey(std::string path, nlohmann::json kept, std::string study, std::string inert_when_zero = "")
      : path(std::move(path)),
        kept(std::move(kept)),
        study(std::move(study)),
        inert_when_zero(std::move(inert_when_zero)) {}
  std::string path;  // from the config's root, e.g. "model.sampler.fill_mode"
  // The value whose behaviour remains (a section: the values of the keys it lists); null: any value (it acted only
  // with another retired key).
  nlohmann::json kept;
  std::string study;  // the lab study that measured it and did not adopt it
  // A sibling key: where the stored section holds it at 0, the retired key acted on nothing, so any value loads.
  std::string inert_when_zero;
};

// Every retired key, in the order of its section.
const std::vector<RetiredKey>& retired_keys();

// Removes the retired keys from a stored config's "model" section (the keys under "model."): silently where the key
// holds the value whose behaviour remains, else fails with an error naming `source`, the key, its value and the
// study. Apply it before the schema reads a stored config, which would refuse the key as unknown.
void strip_retired_keys(nlohmann::json& model_section, const std::string& source);

// The same for a whole stored config (every section), e.g. a checkpoint's "config" or a run's config.json.
void strip_retired_config_keys(nlohmann::json& config, const std::string& source);

}  // namespace isplat

// The table of retired config keys and the helpers that strip them from stored configs.
#include "core/retired_keys.h"

#include "core/error.h"

namespace isplat {

const std::vector<RetiredKey>& retired_keys() {
  static const std::vector<RetiredKey> keys = {
      {"model.sampler.fill_mode", "blend", "lab/2026-11-27-fill-far"},
      {"model.sampler.fill_far_width", nullptr, "lab/2026-11-27-fill-far"},
      {"model.sampler.edge_shift_from", "fixed", "lab/2026-11-29-coverage-shift"},
      {"model.sampler.edge_scale", 1.0, "lab/2026-11-28-crack-side, lab/2026-11-28-edge-near07"},
      {"model.sampler.edge_scale_at", nullptr, "lab/2026-11-28-crack-side, lab/2026-11-28-edge-near07"},
      {"model.sampler.color", "bilinear", "lab/2026-11-23-ablation-edges"},
      {"model.sampler.placement", "random", "lab/2026-11-25-crack-placement, lab/2026-11-25-cracks-edges"},
  };
  return keys;
}

namespace {

// Strips the entries whose path starts with `prefix` from `root` (the section the prefix names).
void strip(nlohmann::json& root, const std::string& prefix, const std::string& source) {
  if (!root.is_object()) return;
  for (const RetiredKey& k : retired_keys()) {
    if (k.path.rfind(prefix, 0) != 0) continue;
    const std::string rest = k.path.substr(prefix.size());
    nlohmann::json* section = &root;
    size_t from = 0, dot;
    while (section != nullptr && (dot = rest.find('.', from)) != std::string::npos) {
      auto it = section->find(rest.substr(from, dot - from));
      section = it != section->end() && it->is_object() ? &*it : nullptr;
      from = dot + 1;
    }
    if (section == nullptr) continue;
    const std::string name = rest.substr(from);
    auto it = section->find(name);
    if (it == section->end()) continue;
    // Numbers compare by value (1 and 1.0 alike); strings and sections exactly.
    const bool kept = k.kept.is_null() || *it == k.kept ||
                      (it->is_number() && k.kept.is_number() && it->get<double>() == k.kept.get<double>());
    if (!kept)
      fail(source, ": ", k.path, " = ", it->dump(), " was retired (its study, ", k.study, ", did not adopt it); only ",
           k.kept.dump(),
           " remains, which is now the only behaviour. Train again, or score it with a build from before the "
           "retirement");
    section->erase(it);
  }
}

}  // namespace

void strip_retired_keys(nlohmann::json& model_section, const std::string& source) {
  strip(model_section, "model.", source);
}

void strip_retired_config_keys(nlohmann::json& config, const std::string& source) {
  strip(config, "", source);
}

}  // namespace isplat

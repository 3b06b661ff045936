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
      {"model.decoder.behind", "shared", "lab/2026-11-28-behind-decoder"},
      {"model.sampler.edge_behind_start", 0, "lab/2026-11-28-behind"},
      {"model.sampler.edge_band_at", "near", "lab/2026-11-28-behind-band", "edge_band"},
      {"model.training_sampler", nlohmann::json::array(), "lab/2026-11-28-seeds"},
      {"model.prior.floor_rule", "best", "lab/2026-11-25-prior-scale"},
      {"model.prior.learned_backbone_lr", 0.0, "lab/2026-11-26-prior-tuned"},
      {"model.prior.learned_input_width", 0, "lab/2026-11-26-prior-tuned"},
      {"model.composer.footprint", 1.0, "lab/2026-12-06-lpips-gap"},
      {"loss.smooth_normal", 0.0, "lab/2026-11-23-ablation-edges"},
      {"loss.depth_grad", 0.0, "lab/2026-11-25-cracks-edges"},
      {"loss.depth_grad_edge", nullptr, "lab/2026-11-25-cracks-edges"},
      {"loss.opacity", 0.0, "lab/2026-11-25-opacity-sparsity"},
      {"train.depth_error",
       {{"scale_sigma", 0.0}, {"warp_sigma", 0.0}, {"blur_px", 0.0}},
       "lab/2026-11-26-depth-error"},
  };
  return keys;
}

namespace {

// Numbers compare by value (1 and 1.0 alike), strings exactly; a kept section is matched by the keys it lists (a
// stored section may hold others, which did nothing without them, and a key it lacks had its default).
bool same(const nlohmann::json& stored, const nlohmann::json& kept) {
  if (stored.is_number() && kept.is_number()) return stored.get<double>() == kept.get<double>();
  if (!kept.is_object()) return stored == kept;
  if (!stored.is_object()) return false;
  for (const auto& [key, value] : kept.items()) {
    const auto it = stored.find(key);
    if (it != stored.end() && !same(*it, value)) return false;
  }
  return true;
}

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
    const auto sibling = k.inert_when_zero.empty() ? section->end() : section->find(k.inert_when_zero);
    const bool inert = sibling != section->end() && sibling->is_number() && sibling->get<double>() == 0.0;
    const bool kept = k.kept.is_null() || inert || same(*it, k.kept);
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

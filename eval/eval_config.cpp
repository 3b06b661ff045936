// Evaluation config schema.
#include "eval/eval_config.h"

#include <cmath>

#include "core/config.h"
#include "core/error.h"

namespace isplat {

void MethodOptions::visit(ConfigVisitor& v) {
  v.field("name", name, "column name in the reports");
  v.field("type", type,
          "model: a checkpoint; lift: the source image lifted on its depth, one Gaussian per pixel; "
          "identity: the source image copied into the target view",
          {"model", "lift", "identity"});
  v.field("checkpoint", checkpoint, "model: checkpoint file (train writes <out>/checkpoints/*.safetensors)");
  v.field("overrides", overrides, "model: overrides of the checkpoint's stored model config, e.g. prior.type=sparse");
  v.field("budgets", budgets,
          "model: support budgets to sweep on the same pairs, one method each: px:<supports per pixel>, "
          "n:<supports>, detail:<supports per pixel at full detail> (see model.sampler.detail_floor)");
  v.section("prune", "model: drop Gaussians that contribute nothing visible after decoding", prune);
}

std::vector<MethodOptions> expand_budget_sweeps(const std::vector<MethodOptions>& methods) {
  std::vector<MethodOptions> out;
  for (const auto& m : methods) {
    if (m.budgets.empty()) {
      out.push_back(m);
      continue;
    }
    ISPLAT_CHECK(m.type == "model", "method '", m.name, "': budgets apply to type model only");
    for (const auto& b : m.budgets) {
      const auto colon = b.find(':');
      const std::string kind = b.substr(0, colon), value = colon == std::string::npos ? "" : b.substr(colon + 1);
      double number = 0;
      try {
        size_t used = 0;
        number = std::stod(value, &used);
        if (used != value.size()) number = -1;
      } catch (const std::exception&) {
        number = -1;
      }
      ISPLAT_CHECK(number > 0 && (kind == "px" || kind == "n" || kind == "detail"), "method '", m.name, "': budget '",
                   b, "' is not px:<per pixel>, n:<count> or detail:<per pixel> with a positive number");
      MethodOptions e = m;
      e.budgets.clear();
      e.name = m.name + "@" + kind + value;
      if (kind == "n") {
        e.overrides.push_back("sampler.budget_mode=fixed");
        e.overrides.push_back("sampler.budget=" + std::to_string(std::llround(number)));
      } else {
        e.overrides.push_back(std::string("sampler.budget_mode=") + (kind == "px" ? "per_pixel" : "detail"));
        e.overrides.push_back("sampler.density=" + value);
      }
      out.push_back(e);
    }
  }
  for (size_t i = 0; i < out.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      ISPLAT_CHECK(out[i].name != out[j].name, "eval: two methods are named '", out[i].name, "'");
  return out;
}

void ScoringOptions::visit(ConfigVisitor& v) {
  v.field("out", out, "output folder: manifests, per-pair results, reports, examples");
  v.field("lpips", lpips, "LPIPS variants to report (squeeze | alex | vgg); unavailable ones are reported as n/a");
  v.field("weights_dir", weights_dir,
          "folder with LPIPS backbones (<net>_features.safetensors) and heads "
          "(lpips_v0.1_<net>_lin.safetensors)");
  v.field("mask_radius", mask_radius, "radius of the morphological closing of the projected mask, pixels",
          Range::at_least(0));
  v.field("examples", examples, "example panels (source, target, prediction, mask) per dataset and method",
          Range::at_least(0));
  v.field("max_per_bin", max_per_bin, "score only the first N pairs of each baseline bin (0 = all; for quick looks)",
          Range::at_least(0));
  v.field("reference", reference,
          "method (after budget expansion, e.g. full@px0.95) every other method is compared with on the same "
          "pairs, with paired bootstrap intervals; empty = no comparison");
  v.section("render", "renderer options for scoring", render);
}

void EvalConfig::visit(ConfigVisitor& v) {
  v.section("runtime", "threads, seed and logging", runtime);
  v.list("datasets", "evaluation datasets", datasets);
  v.section("protocol", "the pair protocol (DESIGN §5)", protocol);
  v.list("methods", "methods scored on the same pairs", methods);
  v.section("scoring", "metrics and outputs", scoring);
}

}  // namespace isplat

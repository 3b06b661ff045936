// Evaluation config schema.
#include "eval/eval_config.h"

#include "core/config.h"

namespace isplat {

void MethodOptions::visit(ConfigVisitor& v) {
  v.field("name", name, "column name in the reports");
  v.field("type", type,
          "model: a checkpoint; lift: the source image lifted on its depth, one Gaussian per pixel; "
          "identity: the source image copied into the target view",
          {"model", "lift", "identity"});
  v.field("checkpoint", checkpoint, "model: checkpoint file (train writes <out>/checkpoints/*.safetensors)");
  v.field("overrides", overrides, "model: overrides of the checkpoint's stored model config, e.g. prior.type=sparse");
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

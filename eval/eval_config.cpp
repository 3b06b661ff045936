// Evaluation config schema.
#include "eval/eval_config.h"

#include <cmath>
#include <sstream>

#include "core/config.h"
#include "core/error.h"
#include "core/paths.h"

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
  v.field("precision", precision,
          "model: the networks' compute precision for this method (fp32, bf16 or auto; empty = runtime.precision): "
          "two methods that differ only here compare bf16 with fp32 on the same pairs",
          {"", "fp32", "bf16", "auto"});
  v.section("prune", "model: drop Gaussians that contribute nothing visible after decoding", prune);
  v.section("perturb", "perturbations of the source view before the method sees it (stability suite)", perturb);
  v.field("sweep_key", sweep_key,
          "sweep one key on the same pairs: an option of this method (perturb.depth_noise) or a model config key "
          "set as an override (override:prior.sparse.prompts); empty = no sweep");
  v.field("sweep_values", sweep_values, "values of sweep_key, one method each");
  v.section("sweep",
            "the budget or sweep point this method was expanded to: written by the evaluator into <out>/config.json "
            "(so that file scores the same methods and results files again); hand-written configs leave it out",
            sweep);
}

Precision method_precision(const MethodOptions& m) {
  return m.precision.empty() ? compute_precision()
                             : resolve_precision(m.precision, cat("methods[].precision of method '", m.name, "'"));
}

namespace {
// The method once per sweep value, each with the key set through the config schema (so types and ranges
// are checked as in a config file).
std::vector<MethodOptions> expand_value_sweep(const MethodOptions& m) {
  ISPLAT_CHECK(!(m.type == "identity" && m.perturb.any_depth()), "method '", m.name,
               "': identity uses no depth, so its depth perturbations would do nothing");
  // A recorded point (an evaluation's config.json) is already expanded.
  ISPLAT_CHECK(
      !m.sweep.any() || (m.sweep_key.empty() && m.budgets.empty() && m.sweep.budget.empty() != m.sweep.key.empty()),
      "method '", m.name,
      "': sweep (a point an evaluation recorded) needs either its key or its budget, and "
      "no sweep_key or budgets beside it");
  if (m.sweep_key.empty()) {
    ISPLAT_CHECK(m.sweep_values.empty(), "method '", m.name, "': sweep_values are given but sweep_key is empty");
    return {m};
  }
  ISPLAT_CHECK(m.budgets.empty(), "method '", m.name,
               "': a value sweep and budgets in one method would mix two series; use two methods");
  ISPLAT_CHECK(!m.sweep_values.empty(), "method '", m.name, "': sweep_key '", m.sweep_key, "' has no sweep_values");
  std::vector<MethodOptions> out;
  const std::string override_prefix = "override:";
  if (m.sweep_key.rfind(override_prefix, 0) == 0) {  // a model config key, set through the method's overrides
    const std::string key = m.sweep_key.substr(override_prefix.size());
    ISPLAT_CHECK(m.type == "model" && !key.empty(), "method '", m.name, "': sweep_key '", m.sweep_key,
                 "' needs a model method and a key after 'override:'");
    for (double value : m.sweep_values) {
      MethodOptions e = m;
      e.sweep_key.clear(), e.sweep_values.clear();
      e.overrides.push_back(key + "=" + cat(value));
      e.sweep = {m.sweep_key, "", value};
      out.push_back(e);
    }
    return out;
  }
  std::stringstream path(m.sweep_key);
  std::vector<std::string> parts;
  for (std::string part; std::getline(path, part, '.');) parts.push_back(part);
  for (double value : m.sweep_values) {
    nlohmann::json j = config_to_json(m);
    j.erase("sweep_key"), j.erase("sweep_values");
    nlohmann::json* node = &j;
    for (size_t k = 0; k < parts.size(); ++k) {
      ISPLAT_CHECK(node->is_object() && node->contains(parts[k]), "method '", m.name, "': sweep_key '", m.sweep_key,
                   "' is not an option of a method");
      node = &(*node)[parts[k]];
    }
    const bool integral = node->is_number_integer();
    *node = integral ? nlohmann::json(std::llround(value)) : nlohmann::json(value);
    MethodOptions e = config_from_json<MethodOptions>(j, cat("method '", m.name, "' sweep"));
    e.sweep = {m.sweep_key, "", integral ? static_cast<double>(std::llround(value)) : value};
    out.push_back(e);
  }
  return out;
}
}  // namespace

std::vector<MethodOptions> expand_sweeps(const std::vector<MethodOptions>& input) {
  std::vector<MethodOptions> methods, out;
  for (const auto& m : input)
    for (auto& e : expand_value_sweep(m)) methods.push_back(std::move(e));
  for (const auto& m : methods) {
    ISPLAT_CHECK(m.type == "model" || m.precision.empty(), "method '", m.name, "': precision '", m.precision,
                 "' applies to type model only (", m.type, " runs no network)");
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
      e.sweep = {"", kind, number};
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
    for (size_t j = 0; j < i; ++j) {
      const std::string a = out[i].label(), b = out[j].label();
      ISPLAT_CHECK(a != b, "eval: two methods are named '", a, "'");
      // Results files are named by safe_name, so such a pair would share (and mix) one file.
      ISPLAT_CHECK(safe_name(a) != safe_name(b), "eval: methods '", b, "' and '", a,
                   "' would share the results file results_", safe_name(a),
                   ".jsonl; rename one (letters, digits, - and _ are kept, anything else becomes _)");
    }
  return out;
}

void check_dataset_names(const std::vector<EvalDatasetOptions>& datasets) {
  ISPLAT_CHECK(!datasets.empty(), "eval: no datasets (config key datasets)");
  for (size_t i = 0; i < datasets.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      ISPLAT_CHECK(safe_name(datasets[i].name) != safe_name(datasets[j].name), "eval: datasets '", datasets[j].name,
                   "' and '", datasets[i].name, "' would share the output folder ", safe_name(datasets[i].name),
                   " (manifest and results); rename one");
}

void ScoringOptions::visit(ConfigVisitor& v) {
  v.field("out", out, "output folder: manifests, per-pair results, reports, examples");
  v.field("lpips", lpips, "LPIPS variants to report (squeeze | alex | vgg); unavailable ones are reported as n/a");
  v.field("weights_dir", weights_dir,
          "folder with LPIPS backbones (<net>_features.safetensors) and heads "
          "(lpips_v0.1_<net>_lin.safetensors); empty = looked up ($INFINISPLAT_WEIGHTS, the checkout's weights/, "
          "~/.cache/infinisplat/weights)");
  v.field("mask_radius", mask_radius, "radius of the morphological closing of the projected mask, pixels",
          Range::at_least(0));
  v.field("mask_depth", mask_depth,
          "the source depth the mask is projected from: true (the dataset's, whatever a method's perturbation does) "
          "or seen (as each method's perturbation leaves it: a sensor's holes go unscored, as on real RGB-D frames "
          "whose only depth is the sensor's; methods with different perturbations are then scored on different "
          "pixels, so compare within one perturbation)",
          {"true", "seen"});
  v.field("examples", examples, "example panels (source, target, prediction, mask) per dataset and method",
          Range::at_least(0));
  v.field("gallery", gallery,
          "failure gallery: this many worst pairs by PSNR, by hole rate and by crack rate per dataset and method, "
          "re-rendered as source, target, prediction, error, rendered normals, alpha and, where the target has depth, "
          "the crack map (red: a farther surface seen through, blue: a nearer one drawn over; 0 = none)",
          Range::between(0, 64));
  v.field("baseline_step", baseline_step, "metres per group of the finer baseline breakdown (report and baseline.png)",
          Range::between(0.01, 100.0));
  v.field("crack_edge_margin", crack_edge_margin,
          "cracks skip neighbour pairs within this many pixels of a reference depth edge, so they count tears in "
          "surfaces, not silhouettes drawn a pixel or two off (0 = every smooth pair, the default measure)",
          Range::between(0, 16));
  v.field("crack_holes", crack_holes,
          "cracks count a smooth neighbour pair with a hole (alpha < 0.5) on either side as broken, instead of "
          "skipping it, so leaving a tear empty is no escape from the measure (false = the default measure)");
  v.field("crack_side", crack_side,
          "cracks count only the broken pairs whose deviant pixel (the one with the larger relative depth error) "
          "renders nearer than the reference (a surface drawn over it: fringes, floaters, silhouettes "
          "too wide) or farther (one seen through it: tears, silhouettes too narrow; holes with crack_holes); any = "
          "both, the default measure; nearer + farther = any on the same pairs",
          {"any", "nearer", "farther"});
  v.field("crack_min_error", crack_min_error,
          "cracks count only the broken pairs whose deviant pixel's rendered depth errs by at least this share of the "
          "reference depth (|z / z_ref - 1|): a large error is another surface seen there, a small one the right "
          "surface slightly off or a blend of two at a soft edge; holes counted by crack_holes always count (0 = every "
          "broken pair, the default measure)",
          Range::between(0.0, 100.0));
  v.field("crack_edge_side", crack_edge_side,
          "cracks count only the broken pairs whose deviant pixel lies, in the reference, on the near side of a depth "
          "edge within 2 px (a silhouette drawn too narrow, or a blend there) or on its far side (what a new view "
          "uncovers beside a silhouette, or a fringe); any = every broken pair, the default measure",
          {"any", "near", "far"});
  v.field("crack_depth", crack_depth,
          "the rendered depth cracks compare with the reference: mean (the weights' mean depth, the default measure: "
          "a pixel that blends a near surface with the one behind it reads in between, so a soft silhouette over a "
          "drawn background breaks where one over nothing does not) or median (the depth of the Gaussian at which "
          "the pixel's transmittance falls to 0.5: the surface it shows, as the reference's point sample does)",
          {"mean", "median"});
  v.field("display_factors", display_factors,
          "also render each target at these multiples of its size (e.g. [2, 4]) and score PSNR and holes against "
          "the target image and mask resized to match: what a viewer above the working size sees (empty = off)",
          Range::between(1.0, 8.0));
  v.field("regions", regions,
          "also score each pair by image region (near and far halves of the target's depth, textured and flat "
          "halves of its gradient energy, silhouettes within 2 px of a depth edge and interiors), with each region's "
          "detail (Laplacian energy against the target's: below 1 = blurrier) and Gaussian density, and render the "
          "source view again against the photo where it has depth (a pure test of the representation); the report gets "
          "a section By image region and by_region.csv");
  v.field("align_scale", align_scale,
          "captures whose units are not metres (COLMAP): scale each method's prediction about the source camera by "
          "the median ratio of reference to rendered depth at the source view's samples before rendering the "
          "target: points (the COLMAP points3D the source view sees), depth (the source view's reference depth); "
          "none (the default) for metric datasets",
          {"none", "points", "depth"});
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

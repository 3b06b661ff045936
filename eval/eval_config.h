// The evaluation configuration: datasets, the pair protocol, the methods to score and how.
#pragma once
#include <string>
#include <vector>

#include "core/precision.h"
#include "core/runtime.h"
#include "data/perturb.h"
#include "eval/datasets.h"
#include "eval/pairs.h"
#include "eval/sweep.h"
#include "render/prune.h"
#include "render/render.h"

namespace isplat {

class ConfigVisitor;

struct MethodOptions {
  std::string name = "model";
  std::string type = "model";          // model | lift | identity
  std::string checkpoint;              // model: checkpoint file
  std::vector<std::string> overrides;  // model: overrides of its stored config, e.g. "prior.type=sparse"
  std::vector<std::string> budgets;    // model: support budgets to sweep ("px:0.5", "n:50000", "detail:1")
  PruneOptions prune;                  // model: pruning after decoding
  PerturbOptions perturb;              // any method: perturbations of the source view (stability suite)
  std::string sweep_key;               // a key of this method's options, e.g. perturb.depth_noise
  std::vector<double> sweep_values;    // ... and the values it takes, one method each
  SweepPoint sweep;                    // the point expand_sweeps made this method for (recorded in config.json)
  std::string precision;               // model: fp32 | bf16 | auto; empty = runtime.precision
  void visit(ConfigVisitor& v);
  MethodId id() const { return {name, sweep}; }
  std::string label() const { return id().label(); }  // unique after expand_sweeps: its results file's name
};

// The precision a model method runs its networks in: its own, else runtime.precision's (in effect process-wide).
Precision method_precision(const MethodOptions& method);

// A method with its name, type and (models) checkpoint and overrides set, the other options at their defaults.
inline MethodOptions named_method(const std::string& name, const std::string& type, const std::string& checkpoint = "",
                                  const std::vector<std::string>& overrides = {}) {
  MethodOptions m;
  m.name = name, m.type = type, m.checkpoint = checkpoint, m.overrides = overrides;
  return m;
}

// A model method with budgets becomes one method per budget, with the sampler overrides appended; a method with
// a sweep becomes one method per value. Each keeps its name and carries its point as `sweep` (its label() is
// e.g. full@px0.5 or full~depth_noise0.02). Other methods pass through. Throws Error naming a malformed budget,
// an unknown sweep key, a value out of range, or two methods whose labels would share one results file.
std::vector<MethodOptions> expand_sweeps(const std::vector<MethodOptions>& methods);

// Throws Error naming two datasets whose names would share one output folder (safe_name), or none at all.
void check_dataset_names(const std::vector<EvalDatasetOptions>& datasets);

struct ScoringOptions {
  std::string out = "out/eval";
  std::vector<std::string> lpips = {"squeeze", "alex", "vgg"};
  std::string weights_dir;  // LPIPS backbones + heads; "" = the weights lookup (core/weights.h)
  int64_t mask_radius = 2;
  std::string mask_depth = "true";  // the mask's source depth: true (unperturbed) | seen (as the perturbation left it)
  int64_t examples = 4;             // example panels saved per dataset and method
  int64_t gallery = 0;              // failure gallery: the worst pairs by PSNR and by hole rate, per dataset and method
  double baseline_step = 0.5;       // metres: the finer baseline groups of the breakdown table
  int64_t max_per_bin = 0;          // score only the first N pairs of each bin (0 = all)
  int64_t crack_edge_margin = 0;    // cracks skip pairs this close (px) to a reference depth edge (0 = none)
  bool crack_holes = false;         // cracks count pairs with a hole on either side as broken (false = skip them)
  std::string crack_side = "any";   // cracks count only broken pairs erring to this side: any | nearer | farther
  double crack_min_error = 0.0;     // cracks count only breaks whose deviant pixel errs by at least this share
  std::string crack_edge_side = "any";  // cracks count only breaks whose deviant pixel lies there: any | near | far
  std::string crack_depth = "mean";     // the rendered depth cracks compare: mean (Σwz / Σw) | median (surface shown)
  std::string reference;                // method the others are compared with, pair by pair (empty = none)
  std::vector<double> display_factors;  // also score each target at these multiples of its size (empty = off)
  bool regions = false;                 // also score by image region and re-render the source view
  std::string align_scale = "none";     // scale each prediction to the dataset: none | points | depth
  RenderOptions render;
  void visit(ConfigVisitor& v);
};

struct EvalConfig {
  RuntimeOptions runtime;
  std::vector<EvalDatasetOptions> datasets;
  ProtocolOptions protocol;
  std::vector<MethodOptions> methods = {named_method("lift", "lift"), named_method("identity", "identity")};
  ScoringOptions scoring;
  void visit(ConfigVisitor& v);
};

}  // namespace isplat

// The experiment configuration: a training recipe, the rows of an ablation table (each a set of config
// switches), the evaluation they are all scored by, and the variants (RGB prior, dataset depth, LiDAR).
#pragma once
#include <string>
#include <vector>

#include "core/runtime.h"

namespace isplat {

class ConfigVisitor;

struct ExperimentRow {
  std::string name;                    // run-folder and method name, e.g. "full", "pixel_supports"
  std::string label;                   // the paper's wording, e.g. "w/o geometry-guided sampling"
  std::vector<std::string> train_set;  // overrides on the training recipe (key=value)
  std::vector<int64_t> seeds = {0};    // one run per seed
  std::string from;                    // reuse this row's runs instead of training (with checkpoint "init")
  std::string checkpoint = "last";     // last | best | init (init = the untrained model, e.g. base Gaussians)
  void visit(ConfigVisitor& v);
};

struct ExperimentVariant {
  std::string name;                    // e.g. "rgb", "depth", "lidar"
  std::vector<std::string> overrides;  // on the model section when loading checkpoints
  std::vector<std::string> rows;       // rows scored in this variant (empty = all)
  void visit(ConfigVisitor& v);
};

struct ExperimentConfig {
  RuntimeOptions runtime;
  std::string out = "out/experiments/ablation";
  std::string train_config;            // the training recipe (JSON) every row starts from
  std::vector<std::string> train_set;  // overrides applied to every row
  std::string eval_config;             // datasets, protocol and scoring (its methods are replaced)
  std::vector<std::string> eval_set;   // overrides on the evaluation config
  std::vector<ExperimentRow> rows;
  std::string reference = "full";  // differences are taken against this row (its seeds averaged per pair)
  std::vector<ExperimentVariant> variants;
  std::vector<std::string> baselines = {"lift", "identity"};  // method types scored beside the rows
  int64_t bootstrap = 2000;                                   // paired bootstrap resamples
  void visit(ConfigVisitor& v);
};

}  // namespace isplat

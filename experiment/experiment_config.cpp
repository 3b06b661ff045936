// Schema of the experiment configuration.
#include "experiment/experiment_config.h"

#include "core/config.h"

namespace isplat {

void ExperimentRow::visit(ConfigVisitor& v) {
  v.field("name", name, "row name: run folder and method name (letters, digits, - and _)");
  v.field("label", label, "the row as the paper words it (e.g. 'w/o implicit decoder')");
  v.field("train_set", train_set, "overrides on the training recipe, key=value (e.g. model.decoder.mode=dense)");
  v.field("seeds", seeds, "training seeds, one run each (with 'from': which of that row's runs to score)",
          Range::at_least(0));
  v.field("from", from, "reuse another row's runs instead of training (e.g. base Gaussians from 'full')");
  v.field("checkpoint", checkpoint, "which checkpoint of each run is scored", {"last", "best", "init"});
}

void ExperimentVariant::visit(ConfigVisitor& v) {
  v.field("name", name, "variant name in method names and reports (e.g. rgb, depth, lidar)");
  v.field("overrides", overrides, "model overrides when loading a checkpoint (e.g. prior.type=dataset)");
  v.field("rows", rows, "rows scored in this variant (empty = every row)");
}

void ExperimentConfig::visit(ConfigVisitor& v) {
  v.section("runtime", "threads, seed and logging", runtime);
  v.field("out", out, "experiment folder: runs/, eval/, report.md|csv|json and charts");
  v.field("train_config", train_config, "the training recipe every row starts from (a train config JSON)");
  v.field("train_set", train_set, "overrides applied to every row's training config");
  v.field("eval_config", eval_config, "evaluation config: datasets, protocol, scoring (its methods are replaced)");
  v.field("eval_set", eval_set, "overrides on the evaluation config");
  v.list("rows", "the rows of the table, each a set of config switches", rows);
  v.field("reference", reference, "the row every other row is compared with");
  v.list("variants", "how checkpoints are scored: prior / depth variants", variants);
  v.field("baselines", baselines, "baseline method types scored beside the rows (lift, identity)");
  v.field("bootstrap", bootstrap, "paired bootstrap resamples for the 95% intervals", Range::at_least(100));
}

}  // namespace isplat

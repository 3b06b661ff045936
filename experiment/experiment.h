// The experiment runner: trains every row of an ablation table from one recipe (resumable, finished runs
// skipped), scores them all on the same manifests in every variant, and writes one report with paired
// bootstrap intervals against the reference row and the training curves of every run.
#pragma once
#include <string>
#include <vector>

#include "experiment/experiment_config.h"

namespace isplat {

struct TrainConfig;

struct ExperimentRun {
  std::string row, dir;  // dir: <out>/runs/<row>_s<seed>
  int64_t seed = 0;
};

class Experiment {
 public:
  explicit Experiment(ExperimentConfig config);

  // Trains the runs of the rows in `only` (empty = all) with a seed in `seeds` (empty = all) that are not
  // finished. Returns false when interrupted (Ctrl-C); the interrupted run resumes next time.
  bool train(const std::vector<std::string>& only = {}, const std::vector<int64_t>& seeds = {});
  // Scores every finished run of the rows in `only` in the variants in `variants` (empty = all), plus the
  // baselines, on the evaluation's manifests.
  void evaluate(const std::vector<std::string>& only = {}, const std::vector<std::string>& variants = {});
  // Writes report.md, report.csv, report.json, curves.png and deltas.png into the experiment folder.
  void report();

  std::vector<ExperimentRun> runs(const ExperimentRow& row) const;  // the runs a row trains or reuses
  bool finished(const ExperimentRun& run) const;                    // trained for the steps the recipe asks
  TrainConfig run_config(const ExperimentRun& run) const;           // the recipe with the row's and the run's keys
  // What a run's stored config.json differs in from what the experiment now gives it ("" when nothing that
  // changes learning differs, or when the run has not started): "key = old there, new now, ...".
  std::string config_drift(const ExperimentRun& run) const;
  // The evaluator's method name of a row's run in a variant: <row>[-s<seed>]@<variant> (seed only when the row
  // has several runs). Generated here and looked up by the same function; never parsed.
  std::string method_name(const ExperimentRow& row, int64_t seed, const ExperimentVariant& variant) const;

 private:
  const ExperimentRow& row(const std::string& name) const;
  // The same three with the run's config already resolved (each resolution reads and validates the recipe).
  bool finished(const ExperimentRun& run, int64_t steps) const;
  std::string config_drift(const ExperimentRun& run, const TrainConfig& want) const;
  void check_config(const ExperimentRun& run, const TrainConfig& want) const;  // fails, naming the keys, on drift

  ExperimentConfig config_;
};

}  // namespace isplat

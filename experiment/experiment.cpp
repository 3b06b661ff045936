// Experiment runner: trains the rows' runs and scores them in every variant (the report: experiment_report.cpp).
#include "experiment/experiment.h"

#include <torch/torch.h>

#include <filesystem>
#include <map>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/retired_keys.h"
#include "eval/evaluator.h"
#include "experiment/scores.h"
#include "io/atomic_file.h"
#include "train/trainer.h"

namespace isplat {
namespace fs = std::filesystem;

using ablation::wanted;

namespace {

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::string join_seeds(const ExperimentRow& r) {
  std::string out;
  for (int64_t s : r.seeds) out += (out.empty() ? "" : ",") + std::to_string(s);
  return out;
}

}  // namespace

Experiment::Experiment(ExperimentConfig config) : config_(std::move(config)) {
  ISPLAT_CHECK(!config_.rows.empty(), "experiment: no rows (config key rows)");
  ISPLAT_CHECK(!config_.train_config.empty(), "experiment: train_config is empty");
  ISPLAT_CHECK(!config_.eval_config.empty(), "experiment: eval_config is empty");
  std::set<std::string> names;
  for (const auto& r : config_.rows) {
    ISPLAT_CHECK(!r.name.empty() && r.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                             "0123456789-_") == std::string::npos,
                 "experiment: row name '", r.name, "' must be letters, digits, - or _ (config key rows[].name)");
    ISPLAT_CHECK(names.insert(r.name).second, "experiment: row '", r.name, "' appears twice");
    ISPLAT_CHECK(!r.seeds.empty() || !r.from.empty(), "experiment: row '", r.name, "' has no seeds");
  }
  for (const auto& r : config_.rows)
    ISPLAT_CHECK(r.from.empty() || names.count(r.from), "experiment: row '", r.name, "' reuses unknown row '", r.from,
                 "' (config key rows[].from)");
  ISPLAT_CHECK(names.count(config_.reference), "experiment: reference row '", config_.reference, "' is not a row");
  if (config_.variants.empty()) config_.variants.push_back({"rgb", {}, {}});
}

const ExperimentRow& Experiment::row(const std::string& name) const {
  for (const auto& r : config_.rows)
    if (r.name == name) return r;
  fail("experiment: no row '", name, "'");
}

std::vector<ExperimentRun> Experiment::runs(const ExperimentRow& r) const {
  const ExperimentRow& src = r.from.empty() ? r : row(r.from);
  std::vector<ExperimentRun> out;
  for (int64_t seed : src.seeds) {
    // A reusing row takes the source's runs with its own seeds (default: seed 0 only; e.g. base Gaussians
    // from a zero-initialized head are the same for every seed).
    if (!r.from.empty() && std::find(r.seeds.begin(), r.seeds.end(), seed) == r.seeds.end()) continue;
    out.push_back({src.name, (fs::path(config_.out) / "runs" / cat(src.name, "_s", seed)).string(), seed});
  }
  return out;
}

TrainConfig Experiment::run_config(const ExperimentRun& run) const {
  const ExperimentRow& r = row(run.row);
  const auto sets = concat(
      concat(config_.train_set, r.train_set),
      {cat("train.out=", run.dir), cat("runtime.seed=", run.seed), cat("runtime.threads=", config_.runtime.threads)});
  return load_config<TrainConfig>(config_.train_config, sets);
}

namespace {
void flatten(const nlohmann::json& j, const std::string& prefix, std::map<std::string, std::string>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      flatten(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), out);
  } else {
    out[prefix] = j.dump();
  }
}
}  // namespace

std::string Experiment::config_drift(const ExperimentRun& run) const {
  return config_drift(run, run_config(run));
}

std::string Experiment::config_drift(const ExperimentRun& run, const TrainConfig& want_config) const {
  const fs::path stored = fs::path(run.dir) / "config.json";
  if (!fs::exists(stored)) return "";
  // Loaded through the schema, so keys added since the run was trained read as their defaults; keys retired since
  // read as the behaviour that remains (core/retired_keys.h).
  std::map<std::string, std::string> had, want;
  nlohmann::json stored_json = parse_json(read_file_bytes(stored.string()), stored.string());
  strip_retired_config_keys(stored_json, stored.string());
  flatten(config_to_json(config_from_json<TrainConfig>(stored_json, stored.string())), "", had);
  flatten(config_to_json(want_config), "", want);
  // Where the run lives, how many threads and workers train it, how long it runs (a longer recipe resumes
  // it), how often it validates and saves, and how many checkpoints it keeps do not change what it learns.
  for (const char* k : {"train.out", "runtime.threads", "data.workers", "train.steps", "train.keep_last",
                        "train.val_every", "train.checkpoint_every", "train.val_images", "data.val_tuples"})
    had.erase(k), want.erase(k);
  std::string diff;
  for (const auto& [k, v] : want) {
    auto it = had.find(k);
    const std::string before = it == had.end() ? "(absent)" : it->second;
    if (before != v) diff += cat(diff.empty() ? "" : ", ", k, " = ", before, " there, ", v, " now");
  }
  for (const auto& [k, v] : had)
    if (!want.count(k)) diff += cat(diff.empty() ? "" : ", ", k, " = ", v, " there, absent now");
  return diff;
}

void Experiment::check_config(const ExperimentRun& run, const TrainConfig& want) const {
  const std::string diff = config_drift(run, want);
  ISPLAT_CHECK(diff.empty(), "experiment: ", run.dir, " (row ", run.row, ", seed ", run.seed,
               ") was trained with another configuration than the experiment now gives it: ", diff,
               ". Nothing was changed; move that folder away (or point `out` elsewhere) to train the row anew");
}

bool Experiment::finished(const ExperimentRun& run) const {
  return finished(run, run_config(run).train.steps);
}

bool Experiment::finished(const ExperimentRun& run, int64_t steps) const {
  const fs::path summary = fs::path(run.dir) / "summary.json";
  if (!fs::exists(summary)) return false;
  const nlohmann::json s = read_json_file(summary.string());
  return guard_json(summary.string(), [&] { return s.value("steps", int64_t{-1}) >= steps; });
}

bool Experiment::train(const std::vector<std::string>& only, const std::vector<int64_t>& seeds) {
  for (const auto& name : only) row(name);  // a misspelt --rows entry fails instead of training nothing
  // The runs to train, in row order; a --seeds value no selected row lists fails before anything trains.
  std::vector<ExperimentRun> todo;
  int64_t trainable = 0;
  for (const auto& r : config_.rows) {
    if (!r.from.empty() || !wanted(only, r.name)) continue;
    ++trainable;
    const size_t before = todo.size();
    for (const auto& run : runs(r))
      if (seeds.empty() || std::find(seeds.begin(), seeds.end(), run.seed) != seeds.end()) todo.push_back(run);
    if (todo.size() == before)
      log_warn("experiment: --seeds selects no run of row '", r.name, "' (its seeds: ", join_seeds(r),
               "; add the seed to the row's seeds in the config)");
  }
  ISPLAT_CHECK(seeds.empty() || trainable == 0 || !todo.empty(),
               "experiment: --seeds selects no run to train (a seed must be listed in the row's seeds)");
  for (const auto& run : todo) {
    const TrainConfig tc = run_config(run);
    check_config(run, tc);
    if (finished(run, tc.train.steps)) {
      log_info("experiment: ", run.row, " seed ", run.seed, " is trained (", run.dir, "); skipped");
      continue;
    }
    log_info("experiment: training ", run.row, " seed ", run.seed, " -> ", run.dir);
    Trainer trainer(tc);
    trainer.resume("auto");
    if (trainer.run() == 130) return false;
  }
  return true;
}

std::string Experiment::method_name(const ExperimentRow& r, int64_t seed, const ExperimentVariant& v) const {
  const size_t seeds = runs(r).size();
  return cat(r.name, seeds > 1 ? cat("-s", seed) : std::string(), "@", v.name);
}

namespace {
// The first weights file a variant's overrides name that does not exist ("" if none): such a variant is
// skipped with a warning, so one missing prior does not stop the other variants' scoring.
std::string missing_weights(const std::vector<std::string>& overrides) {
  for (const auto& o : overrides)
    for (const std::string key : {"prior.learned_weights=", "prior.torchscript="})
      if (o.rfind(key, 0) == 0 && !fs::exists(o.substr(key.size()))) return o.substr(key.size());
  return "";
}
}  // namespace

void Experiment::evaluate(const std::vector<std::string>& only, const std::vector<std::string>& variants) {
  for (const auto& name : only) row(name);
  for (const auto& name : variants) {
    bool known = false;
    for (const auto& v : config_.variants) known = known || v.name == name;
    ISPLAT_CHECK(known, "experiment: no variant '", name, "' (--variants; the config's variants[].name)");
  }
  EvalConfig ec = load_config<EvalConfig>(config_.eval_config, config_.eval_set);
  ec.runtime.threads = config_.runtime.threads;
  ec.scoring.out = (fs::path(config_.out) / "eval").string();
  ec.methods.clear();
  for (const auto& b : config_.baselines) ec.methods.push_back(named_method(b, b));
  for (const auto& v : config_.variants) {
    if (!wanted(variants, v.name)) continue;
    if (const std::string missing = missing_weights(v.overrides); !missing.empty()) {
      log_warn("experiment: variant '", v.name, "' needs ", missing, ", which does not exist yet; not scored");
      continue;
    }
    for (const auto& r : config_.rows) {
      if (!wanted(only, r.name) || (!v.rows.empty() && !wanted(v.rows, r.name))) continue;
      for (const auto& run : runs(r)) {
        const std::string ck = (fs::path(run.dir) / "checkpoints" / (r.checkpoint + ".safetensors")).string();
        const TrainConfig want = run_config(run);
        if (!fs::exists(ck) || (r.checkpoint != "init" && !finished(run, want.train.steps))) {
          log_warn("experiment: ", r.name, " seed ", run.seed, " is not trained yet (", ck, "); not scored");
          continue;
        }
        check_config(run, want);
        ec.methods.push_back(named_method(method_name(r, run.seed, v), "model", ck, v.overrides));
      }
    }
  }
  Evaluator(ec).run();
}

}  // namespace isplat

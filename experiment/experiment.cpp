// Experiment runner: training rows, scoring variants, and the paired report.
#include "experiment/experiment.h"

#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/retired_keys.h"
#include "eval/evaluator.h"
#include "eval/results_log.h"
#include "io/atomic_file.h"
#include "io/chart.h"
#include "io/jsonl.h"
#include "io/table.h"
#include "metrics/stats.h"
#include "train/trainer.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

bool wanted(const std::vector<std::string>& only, const std::string& name) {
  return only.empty() || std::find(only.begin(), only.end(), name) != only.end();
}

std::string join_seeds(const ExperimentRow& r) {
  std::string out;
  for (int64_t s : r.seeds) out += (out.empty() ? "" : ",") + std::to_string(s);
  return out;
}

std::string signed_fmt(double v, int digits) {
  return (v >= 0 ? "+" : "") + format_fixed(v, digits);
}

std::string interval_fmt(const Interval& i, int digits) {  // "+0.12 [+0.05, +0.20]"
  return cat(signed_fmt(i.mean, digits), " [", signed_fmt(i.lo, digits), ", ", signed_fmt(i.hi, digits), "]");
}

double mean_finite(const std::vector<double>& v) {
  double s = 0;
  int64_t n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++n;
  return n ? s / n : std::numeric_limits<double>::quiet_NaN();
}

// The commit a finished run's summary names ("not recorded" for runs finished before commits were recorded).
std::string trained_by(const std::string& run_dir) {
  const fs::path summary = fs::path(run_dir) / "summary.json";
  if (!fs::exists(summary)) return "not finished";
  const nlohmann::json s = read_json_file(summary.string());
  return s.contains("commit") && s["commit"].is_string() ? s["commit"].get<std::string>() : "not recorded";
}

// One scored method's values on the experiment's pair list (NaN where not scored).
struct Scores {
  std::vector<double> psnr, ssim, lpips;
  std::vector<double> holes, cracks, normals;  // stability measures in % and degrees (NaN where not measured)
  bool any = false;
};

// `v` with the pairs outside baseline bin `bin` set to NaN (bin < 0: all pairs).
std::vector<double> in_bin(const std::vector<double>& v, const std::vector<int>& pair_bin, int bin) {
  if (bin < 0) return v;
  std::vector<double> out;
  for (size_t k = 0; k < v.size(); ++k) out.push_back(pair_bin[k] == bin ? v[k] : NAN);
  return out;
}

// One row of report.csv / report.json: a row's means on one bin and its differences to the reference.
struct TableRow {
  std::string row, label, bin;
  int64_t pairs = 0;
  double psnr = NAN, ssim = NAN, lpips = NAN, holes = NAN, cracks = NAN, normals = NAN;
  Interval dp, dl, dh, dc;  // PSNR, LPIPS, holes, cracks minus the reference
  std::string interval;     // what the intervals resample: "pairs" or "seeds and pairs"
};

// report.csv and report.json: the columns, declared once.
Table results_table(const std::string& lp) {
  Table t;
  t.columns = {{"dataset"}, {"variant"}, {"reference"}, {"label"},   {"row"},
               {"bin"},     {"pairs"},   {"psnr", 4},   {"ssim", 5}, {"lpips_" + lp, 5}};
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"delta_psnr", 4},
                                                                 {"delta_psnr_lo", 4},
                                                                 {"delta_psnr_hi", 4},
                                                                 {"delta_lpips", 5},
                                                                 {"delta_lpips_lo", 5},
                                                                 {"delta_lpips_hi", 5},
                                                                 {"holes_pct", 4},
                                                                 {"cracks_pct", 4},
                                                                 {"normals_deg", 3},
                                                                 {"delta_holes", 4},
                                                                 {"delta_holes_lo", 4},
                                                                 {"delta_holes_hi", 4},
                                                                 {"delta_cracks", 4},
                                                                 {"delta_cracks_lo", 4},
                                                                 {"delta_cracks_hi", 4},
                                                                 {"interval"}})
    t.columns.push_back(c);
  return t;
}

void add_result(Table& table, const std::string& dataset, const std::string& variant, const std::string& reference,
                const TableRow& t) {
  std::vector<TableCell> cells = {dataset, variant, reference, t.label, t.row, t.bin, t.pairs, t.psnr, t.ssim, t.lpips};
  auto add_interval = [&](const Interval& i) { cells.insert(cells.end(), {i.mean, i.lo, i.hi}); };
  add_interval(t.dp), add_interval(t.dl);
  cells.insert(cells.end(), {t.holes, t.cracks, t.normals});
  add_interval(t.dh), add_interval(t.dc);
  cells.push_back(t.interval);
  table.add(std::move(cells));
}

// One run's (or baseline's) scores against `base` on one bin (-1 = all pairs): means and paired intervals.
TableRow on_bin(const Scores& s, const Scores& base, const std::vector<int>& pair_bin, int bin, int64_t resamples) {
  auto sub = [&](const std::vector<double>& v) { return in_bin(v, pair_bin, bin); };
  TableRow t;
  const std::vector<double> p = sub(s.psnr);
  for (double x : p) t.pairs += std::isfinite(x);
  t.psnr = mean_finite(p), t.ssim = mean_finite(sub(s.ssim)), t.lpips = mean_finite(sub(s.lpips));
  t.holes = mean_finite(sub(s.holes)), t.cracks = mean_finite(sub(s.cracks));
  t.normals = mean_finite(sub(s.normals));
  t.dp = paired_bootstrap(p, sub(base.psnr), resamples);
  t.dl = paired_bootstrap(sub(s.lpips), sub(base.lpips), resamples);
  t.dh = paired_bootstrap(sub(s.holes), sub(base.holes), resamples);
  t.dc = paired_bootstrap(sub(s.cracks), sub(base.cracks), resamples);
  t.interval = "pairs";
  return t;
}
// A row over its training seeds against the reference's same seeds (mine[k] and ref[k] share seed k) on one bin:
// means over the seeds, and seed-aware intervals (seed_paired_bootstrap).
TableRow over_seeds(const std::vector<Scores>& mine, const std::vector<Scores>& ref, const std::vector<int>& pair_bin,
                    int bin, int64_t resamples) {
  TableRow t;
  t.interval = "seeds and pairs";
  auto per_seed = [&](const std::vector<Scores>& rows, std::vector<double> Scores::*m) {
    std::vector<std::vector<double>> out;
    for (const auto& s : rows) out.push_back(in_bin(s.*m, pair_bin, bin));
    return out;
  };
  auto seed_mean = [&](std::vector<double> Scores::*m) {
    double sum = 0;
    for (const auto& v : per_seed(mine, m)) sum += mean_finite(v);
    return sum / double(mine.size());
  };
  auto delta = [&](std::vector<double> Scores::*m) {
    return seed_paired_bootstrap(per_seed(mine, m), per_seed(ref, m), resamples);
  };
  t.psnr = seed_mean(&Scores::psnr), t.ssim = seed_mean(&Scores::ssim), t.lpips = seed_mean(&Scores::lpips);
  t.holes = seed_mean(&Scores::holes), t.cracks = seed_mean(&Scores::cracks), t.normals = seed_mean(&Scores::normals);
  t.dp = delta(&Scores::psnr), t.dl = delta(&Scores::lpips), t.dh = delta(&Scores::holes),
  t.dc = delta(&Scores::cracks);
  t.pairs = t.dp.n;
  return t;
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

namespace {
// One dataset's scores on the experiment's pairs: what every variant's tables read.
struct DatasetScores {
  std::string name;
  std::vector<std::string> bins;
  std::vector<int64_t> bin_counts;
  std::vector<int> pair_bin;                       // each pair's baseline bin
  std::function<Scores(const std::string&)> load;  // a scored method's values (none when it has no results)
};

// One line of a variant's tables: a trained run, a baseline, or the reference's seeds against each other.
struct Entry {
  std::string name, label;
  Scores s;
  bool is_ref_seed = false, is_baseline = false, spread = false;
};

// The reference row's seeds in variant v, and their average per pair (none when it is not scored there).
std::vector<std::pair<int64_t, Scores>> reference_seeds(const Experiment& ex, const ExperimentConfig& c,
                                                        const DatasetScores& ds, const ExperimentVariant& v) {
  std::vector<std::pair<int64_t, Scores>> out;
  for (const auto& r : c.rows)
    if (r.name == c.reference)
      for (const auto& run : ex.runs(r))
        if (Scores s = ds.load(ex.method_name(r, run.seed, v)); s.any) out.push_back({run.seed, s});
  return out;
}

Scores seed_average(const std::vector<std::pair<int64_t, Scores>>& seeds, size_t pairs) {
  Scores ref;
  ref.any = true;
  for (size_t k = 0; k < pairs; ++k) {
    auto avg = [&](std::vector<double> Scores::*member) {
      double sum = 0;
      int n = 0;
      for (const auto& [seed, s] : seeds)
        if (std::isfinite((s.*member)[k])) sum += (s.*member)[k], ++n;
      return n == static_cast<int>(seeds.size()) ? sum / n : NAN;
    };
    for (auto m : {&Scores::psnr, &Scores::ssim, &Scores::lpips, &Scores::holes, &Scores::cracks, &Scores::normals})
      (ref.*m).push_back(avg(m));
  }
  return ref;
}

// Every trained row and seed scored in variant v, then the baselines, then the reference's seed spread.
std::vector<Entry> variant_entries(const Experiment& ex, const ExperimentConfig& c, const DatasetScores& ds,
                                   const ExperimentVariant& v, const std::vector<std::pair<int64_t, Scores>>& ref) {
  std::vector<Entry> entries;
  for (const auto& r : c.rows) {
    if (!v.rows.empty() && !wanted(v.rows, r.name)) continue;
    for (const auto& run : ex.runs(r)) {
      const std::string name = ex.method_name(r, run.seed, v);
      if (Scores s = ds.load(name); s.any)
        entries.push_back({name, r.label.empty() ? r.name : r.label, s, r.name == c.reference});
    }
  }
  for (const auto& b : c.baselines)
    if (Scores s = ds.load(b); s.any) entries.push_back({b, b, s, false, true});
  if (ref.size() > 1)  // training noise: the reference's seeds against each other
    entries.push_back(
        {cat(c.reference, " seed spread"), "seed 1 - seed 0 of the reference", ref[1].second, false, false, true});
  return entries;
}

// The variant's tables in report.md: scores with intervals per bin, and stability; their rows go into
// `results`, each entry's PSNR difference per bin into `chart`, and the entries without stability measures into
// `unmeasured_note`.
std::string entry_tables(const ExperimentConfig& c, const DatasetScores& ds, const ExperimentVariant& v,
                         const std::vector<Entry>& entries, const std::vector<std::pair<int64_t, Scores>>& ref_seeds,
                         const Scores& ref, const std::string& lp, Table& results, Chart& chart,
                         std::string& unmeasured_note) {
  const int last_bin = static_cast<int>(ds.bins.size()) - 1;
  const std::string& far_bin = ds.bins[static_cast<size_t>(last_bin)];
  Table scores, stability;
  scores.columns = {
      {"row"}, {"PSNR", 2}, {"SSIM", 3}, {"LPIPS (" + lp + ")", 3}, {"ΔPSNR [95% CI]"}, {"ΔLPIPS [95% CI]"}};
  for (const auto& b : ds.bins) scores.columns.push_back({b + " PSNR (Δ [CI])"});
  stability.columns = {{"row"},
                       {"holes %", 2},
                       {"cracks %", 2},
                       {"normals deg", 1},
                       {far_bin + " holes % (Δ [CI])"},
                       {far_bin + " cracks % (Δ [CI])"}};
  std::vector<std::string> unmeasured;  // rows scored before the stability measures existed
  for (size_t k = 0; k < entries.size(); ++k) {
    const Entry& e = entries[k];
    const Scores& base = e.spread ? ref_seeds[0].second : ref;
    const bool self = e.is_ref_seed && ref_seeds.size() == 1;
    std::vector<TableRow> on;  // [0]: all pairs, [b + 1]: bin b
    for (int b = -1; b <= last_bin; ++b) {
      on.push_back(on_bin(e.s, base, ds.pair_bin, b, c.bootstrap));
      on.back().row = e.name, on.back().label = e.label, on.back().bin = b < 0 ? "all" : ds.bins[size_t(b)];
      add_result(results, ds.name, v.name, c.reference, on.back());
    }
    const TableRow &all = on.front(), &far = on.back();
    std::vector<TableCell> cells = {e.name + (e.label != e.name ? " (" + e.label + ")" : ""),
                                    all.psnr,
                                    all.ssim,
                                    all.lpips,
                                    self ? "reference" : interval_fmt(all.dp, 2),
                                    self ? "reference" : interval_fmt(all.dl, 3)};
    ChartSeries series;
    series.name = e.name;
    series.marker = static_cast<int>(k % 4);
    for (size_t b = 0; b < ds.bins.size(); ++b) {
      const TableRow& t = on[b + 1];
      cells.push_back(format_fixed(t.psnr, 2) + (!self && t.dp.n > 0 ? " (" + interval_fmt(t.dp, 2) + ")" : ""));
      series.x.push_back(static_cast<double>(b));
      series.y.push_back(self ? 0.0 : t.dp.mean);
    }
    scores.add(std::move(cells));
    // Baselines sit many dB away and would squash the rows' differences: they stay in the tables.
    if (!self && !e.spread && !e.is_baseline) chart.series.push_back(series);
    if (!std::isfinite(all.holes)) {
      unmeasured.push_back(e.name);
      continue;
    }
    auto with_interval = [&](double v, const Interval& i) {
      return format_fixed(v, 2) + (self || i.n == 0 ? std::string() : " (" + interval_fmt(i, 2) + ")");
    };
    stability.add({e.name, all.holes, all.cracks, all.normals, with_interval(far.holes, far.dh),
                   with_interval(far.cracks, far.dc)});
  }
  std::string md = table_markdown(scores) + "\n";
  if (stability.rows.empty()) return md;
  md +=
      cat("Stability (holes: masked pixels with rendered alpha < 0.5; cracks: neighbours whose rendered depth jumps "
          "where the reference is smooth; normals: mean angle between neighbouring rendered normals on "
          "reference-planar surfaces). Δ to `",
          c.reference, "` with a paired 95% interval:\n\n", table_markdown(stability), "\n");
  if (!unmeasured.empty()) {
    std::string& md = unmeasured_note;
    md +=
        "Without holes and cracks (the method renders no alpha, like identity, or was scored before they were "
        "measured: delete its results_*.jsonl and stamp to score it again):";
    for (const auto& n : unmeasured) md += " " + n;
    md += ".\n\n";
  }
  return md;
}

// Rows over their training seeds, seed k against the reference's seed k: the intervals resample seeds as well
// as pairs, so they hold training noise, which the per-run intervals leave out. The runs' scores are those of
// `entries`, not read again.
std::string seed_table(const Experiment& ex, const ExperimentConfig& c, const DatasetScores& ds,
                       const ExperimentVariant& v, const std::vector<Entry>& entries,
                       const std::vector<std::pair<int64_t, Scores>>& ref_seeds, Table& results) {
  const int last_bin = static_cast<int>(ds.bins.size()) - 1;
  const std::string& far_bin = ds.bins[static_cast<size_t>(last_bin)];
  auto scored = [&](const std::string& name) -> const Scores* {
    for (const Entry& e : entries)
      if (!e.is_baseline && e.name == name) return &e.s;
    return nullptr;
  };
  Table t;
  t.columns = {{"row"},
               {"PSNR", 2},
               {"ΔPSNR [95% CI]"},
               {"ΔLPIPS [95% CI]"},
               {far_bin + " Δholes % [CI]"},
               {far_bin + " Δcracks % [CI]"},
               {"per seed: ΔPSNR / " + far_bin + " Δholes / Δcracks"}};
  for (const auto& r : c.rows) {
    if (r.name == c.reference || (!v.rows.empty() && !wanted(v.rows, r.name))) continue;
    std::vector<Scores> mine, theirs;
    std::string seeds;
    std::vector<int64_t> seed_ids;
    for (const auto& run : ex.runs(r)) {
      const auto it = std::find_if(ref_seeds.begin(), ref_seeds.end(), [&](auto& s) { return s.first == run.seed; });
      const Scores* s = it == ref_seeds.end() ? nullptr : scored(ex.method_name(r, run.seed, v));
      if (s == nullptr) continue;
      mine.push_back(*s), theirs.push_back(it->second);
      seeds += cat(seeds.empty() ? "" : "+", run.seed);
      seed_ids.push_back(run.seed);
    }
    if (mine.size() < 2) continue;
    const std::string name = cat(r.name, "@", v.name, " seeds ", seeds);
    std::vector<TableRow> on;  // [0]: all pairs, [b + 1]: bin b
    for (int b = -1; b <= last_bin; ++b) {
      on.push_back(over_seeds(mine, theirs, ds.pair_bin, b, c.bootstrap));
      on.back().row = name, on.back().label = r.label.empty() ? r.name : r.label;
      on.back().bin = b < 0 ? "all" : ds.bins[static_cast<size_t>(b)];
      add_result(results, ds.name, v.name, c.reference, on.back());
    }
    const TableRow &all = on.front(), &far = on.back();
    // Each seed against its own reference seed, so a reader sees whether the seeds agree in sign.
    std::string per_seed;
    for (size_t k = 0; k < mine.size(); ++k) {
      auto delta = [&](std::vector<double> Scores::*m, int bin) {  // the paired mean difference
        return paired_bootstrap(in_bin(mine[k].*m, ds.pair_bin, bin), in_bin(theirs[k].*m, ds.pair_bin, bin), 1).mean;
      };
      per_seed +=
          cat(k ? "; " : "", "s", seed_ids[k], " ", signed_fmt(delta(&Scores::psnr, -1), 2), " / ",
              signed_fmt(delta(&Scores::holes, last_bin), 2), " / ", signed_fmt(delta(&Scores::cracks, last_bin), 2));
    }
    t.add({name, all.psnr, interval_fmt(all.dp, 2), interval_fmt(all.dl, 3), far.dh.n ? interval_fmt(far.dh, 2) : "n/a",
           far.dc.n ? interval_fmt(far.dc, 2) : "n/a", per_seed});
  }
  if (t.rows.empty()) return "";
  return cat("Rows over their training seeds: seed k of a row against seed k of `", c.reference,
             "`, averaged over the seeds both have; the interval resamples the seeds as well as the pairs, so it "
             "holds training noise, which the per-run rows above leave out. With two seeds it is crude (a bootstrap "
             "of two seeds understates their spread):\n\n",
             table_markdown(t), "\n");
}

// One variant's section of report.md.
std::string variant_section(const Experiment& ex, const ExperimentConfig& c, const DatasetScores& ds,
                            const ExperimentVariant& v, const std::string& lp, Table& results,
                            std::vector<Chart>& deltas) {
  const auto ref_seeds = reference_seeds(ex, c, ds, v);
  if (ref_seeds.empty())
    return cat("### ", v.name, "\n\nThe reference row `", c.reference, "` is not scored in this variant yet.\n\n");
  std::string md = "### " + v.name;
  for (size_t k = 0; k < v.overrides.size(); ++k) md += (k ? ", `" : " (model overrides: `") + v.overrides[k] + "`";
  md += v.overrides.empty() ? "\n\n" : ")\n\n";
  Chart chart;
  chart.title = cat(ds.name, " / ", v.name, ": PSNR minus ", c.reference, " per baseline bin");
  chart.x_label = "baseline bin (0 = smallest)";
  chart.y_label = "delta PSNR (dB), mean over the bin's pairs";
  const std::vector<Entry> entries = variant_entries(ex, c, ds, v, ref_seeds);
  const Scores ref = seed_average(ref_seeds, ds.pair_bin.size());
  std::string unmeasured;
  md += entry_tables(c, ds, v, entries, ref_seeds, ref, lp, results, chart, unmeasured);
  md += seed_table(ex, c, ds, v, entries, ref_seeds, results) + unmeasured;
  deltas.push_back(chart);
  return md;
}

// The training runs' table, and their curves: loss and validation PSNR against step and against CPU time.
std::string training_section(const Experiment& ex, const ExperimentConfig& c, std::vector<Chart>& curves) {
  Chart loss_step{"training loss (total) vs step", "step", "loss", false, {}};
  Chart val_step{"validation masked PSNR vs step", "step", "PSNR (dB)", false, {}};
  Chart loss_cpu{"training loss (total) vs CPU time", "CPU time (s)", "loss", false, {}};
  Chart val_cpu{"validation masked PSNR vs CPU time", "CPU time (s)", "PSNR (dB)", false, {}};
  Table t;
  t.columns = {{"run"},
               {"steps"},
               {"mean step (ms)", 0},
               {"CPU time (s)", 1},
               {"final val PSNR (dB)", 2},
               {"trained by commit"}};
  int color = 0;
  for (const auto& r : c.rows) {
    if (!r.from.empty()) continue;
    for (const auto& run : ex.runs(r)) {
      const std::string log_path = (fs::path(run.dir) / "train_log.jsonl").string();
      const auto records = read_jsonl(log_path);
      if (records.empty()) continue;
      const int marker = (color / 10) % 4;  // tab10 repeats after 10 runs: the marker tells them apart
      ChartSeries ls{cat(r.name, "_s", run.seed), {}, {}, true, -1, color},
          vs{cat(r.name, "_s", run.seed), {}, {}, true, marker, color};
      ChartSeries lc = ls, vc = vs;
      double last_val = NAN, cpu = 0, step_ms = 0;
      int64_t steps = 0, timed = 0;
      std::vector<double> window;
      for (const auto& j : records)
        guard_json(log_path, [&] {
          const double step = j.value("step", 0.0);
          cpu = j.value("cpu_s", cpu);
          if (j.contains("loss") && j["loss"].contains("total") && j["loss"]["total"].is_number()) {
            window.push_back(j["loss"]["total"].get<double>());
            if (window.size() > 20) window.erase(window.begin());
            double sm = 0;
            for (double x : window) sm += x;
            ls.x.push_back(step), ls.y.push_back(sm / window.size());  // 20-step moving average
            lc.x.push_back(cpu), lc.y.push_back(sm / window.size());
            steps = static_cast<int64_t>(step);
            if (j.contains("step_ms") && j["step_ms"].is_number()) step_ms += j["step_ms"].get<double>(), ++timed;
          }
          if (j.contains("val_psnr_masked") && j["val_psnr_masked"].is_number()) {
            last_val = j["val_psnr_masked"].get<double>();
            vs.x.push_back(step), vs.y.push_back(last_val);
            vc.x.push_back(cpu), vc.y.push_back(last_val);
          }
        });
      loss_step.series.push_back(ls), val_step.series.push_back(vs);
      loss_cpu.series.push_back(lc), val_cpu.series.push_back(vc);
      t.add({cat(r.name, "_s", run.seed), steps, timed ? step_ms / timed : NAN, cpu, last_val, trained_by(run.dir)});
      ++color;
    }
  }
  curves = {loss_step, val_step, loss_cpu, val_cpu};
  return "## Training runs\n\n" + table_markdown(t);
}

// The scores of dataset d on the experiment's pairs, or nothing when it was not evaluated yet.
std::optional<DatasetScores> dataset_scores(const Evaluator& ev, const EvalConfig& ec, size_t d,
                                            const std::string& lp) {
  const std::string manifest_path = (fs::path(ev.dataset_dir(d)) / "manifest.json").string();
  if (!fs::exists(manifest_path)) return std::nullopt;
  auto m = std::make_shared<Manifest>(read_manifest(manifest_path));
  const std::vector<int64_t> pairs = ev.select_pairs(*m);
  DatasetScores ds;
  ds.name = ec.datasets[d].name;
  for (size_t b = 0; b < m->bin_counts.size(); ++b) ds.bins.push_back(m->bin_label(static_cast<int>(b)));
  ds.bin_counts.assign(m->bin_counts.begin(), m->bin_counts.end());
  for (int64_t i : pairs) ds.pair_bin.push_back(m->pairs[static_cast<size_t>(i)].bin);
  ds.load = [&ev, d, m, pairs, lp](const std::string& method) {
    Scores s;
    const std::string path = ev.results_path(d, method);
    if (!fs::exists(path)) return s;
    const ResultsLog log(path, [&](const PairResult& r) { return check_against_manifest(r, *m); });
    for (int64_t i : pairs) {
      auto it = log.done().find(i);
      const bool ok = it != log.done().end();
      s.any |= ok;
      s.psnr.push_back(ok ? it->second.psnr : NAN);
      s.ssim.push_back(ok ? it->second.ssim : NAN);
      s.lpips.push_back(ok && it->second.lpips.count(lp) ? it->second.lpips.at(lp) : NAN);
      s.holes.push_back(ok ? 100 * it->second.hole_rate : NAN);
      s.cracks.push_back(ok ? 100 * it->second.crack_rate : NAN);
      s.normals.push_back(ok ? it->second.normal_deg : NAN);
    }
    return s;
  };
  return ds;
}
}  // namespace

void Experiment::report() {
  EvalConfig ec = load_config<EvalConfig>(config_.eval_config, config_.eval_set);
  ec.scoring.out = (fs::path(config_.out) / "eval").string();
  ec.scoring.lpips = {};  // the report reads scores; it computes none
  const Evaluator ev(ec);
  const std::string lp = "squeeze";  // the LPIPS variant reported (the one with real weights here)
  std::string md = cat("# Ablation report\n\nEvery row is trained from the same recipe (`", config_.train_config,
                       "`) and scored on the same pairs with the same masks. Delta = row minus `", config_.reference,
                       "` on the same pairs (its seeds averaged per pair), with a paired bootstrap 95% interval (",
                       config_.bootstrap, " resamples); an interval that contains 0 is no difference.\n\n");
  Table results = results_table(lp);
  std::vector<Chart> deltas, curves;
  for (size_t d = 0; d < ec.datasets.size(); ++d) {
    const auto ds = dataset_scores(ev, ec, d, lp);
    if (!ds) {
      md += cat("## ", ec.datasets[d].name, "\n\nNot evaluated yet (no ",
                (fs::path(ev.dataset_dir(d)) / "manifest.json").string(), ").\n\n");
      continue;
    }
    md += cat("## ", ds->name, " (", ds->pair_bin.size(), " pairs; per bin:");
    for (size_t b = 0; b < ds->bins.size(); ++b) md += cat(" ", ds->bins[b], " ", ds->bin_counts[b]);
    md += ")\n\n";
    for (const auto& v : config_.variants) md += variant_section(*this, config_, *ds, v, lp, results, deltas);
  }
  md += cat("Report written by commit ", build_commit(), ".\n\n", training_section(*this, config_, curves),
            "\nCharts: `curves.png` (training curves), `deltas.png` (ΔPSNR per baseline bin).\n");
  const fs::path out(config_.out);
  fs::create_directories(out);
  write_charts((out / "curves.png").string(), curves);
  write_charts((out / "deltas.png").string(), deltas.empty() ? std::vector<Chart>{Chart{}} : deltas);
  write_file_atomic((out / "report.md").string(), md);
  write_table_csv((out / "report.csv").string(), results);
  write_table_json((out / "report.json").string(), results);
  log_info("experiment: report in ", config_.out, " (report.md, report.csv, report.json, curves.png, deltas.png)");
}

}  // namespace isplat

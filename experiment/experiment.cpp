// Experiment runner: training rows, scoring variants, and the paired report.
#include "experiment/experiment.h"

#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
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
#include "io/csv.h"
#include "io/jsonl.h"
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

std::string fmt(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

std::string signed_fmt(double v, int digits) {
  return (v >= 0 ? "+" : "") + fmt(v, digits);
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

void add_table_row(CsvTable& csv, nlohmann::ordered_json& js, const std::string& dataset, const std::string& variant,
                   const std::string& reference, const std::string& lp, const TableRow& t) {
  std::vector<std::string> cells = {dataset,        variant,        t.row,          t.bin, std::to_string(t.pairs),
                                    fmt(t.psnr, 4), fmt(t.ssim, 5), fmt(t.lpips, 5)};
  auto add_interval = [&](const Interval& i, int digits) {
    for (double x : {i.mean, i.lo, i.hi}) cells.push_back(fmt(x, digits));
  };
  add_interval(t.dp, 4), add_interval(t.dl, 5);
  cells.insert(cells.end(), {fmt(t.holes, 4), fmt(t.cracks, 4), fmt(t.normals, 3)});
  add_interval(t.dh, 4), add_interval(t.dc, 4);
  cells.push_back(t.interval);
  csv.rows.push_back(std::move(cells));
  auto num = [](double x) { return std::isfinite(x) ? nlohmann::ordered_json(x) : nlohmann::ordered_json(nullptr); };
  js.push_back({{"dataset", dataset},
                {"variant", variant},
                {"row", t.row},
                {"label", t.label},
                {"bin", t.bin},
                {"pairs", t.pairs},
                {"psnr", num(t.psnr)},
                {"ssim", num(t.ssim)},
                {"lpips_" + lp, num(t.lpips)},
                {"delta_psnr", num(t.dp.mean)},
                {"delta_psnr_ci", {num(t.dp.lo), num(t.dp.hi)}},
                {"delta_lpips", num(t.dl.mean)},
                {"delta_lpips_ci", {num(t.dl.lo), num(t.dl.hi)}},
                {"holes_pct", num(t.holes)},
                {"cracks_pct", num(t.cracks)},
                {"normals_deg", num(t.normals)},
                {"delta_holes", num(t.dh.mean)},
                {"delta_holes_ci", {num(t.dh.lo), num(t.dh.hi)}},
                {"delta_cracks", num(t.dc.mean)},
                {"delta_cracks_ci", {num(t.dc.lo), num(t.dc.hi)}},
                {"reference", reference},
                {"interval", t.interval}});
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

void Experiment::report() {
  EvalConfig ec = load_config<EvalConfig>(config_.eval_config, config_.eval_set);
  ec.scoring.out = (fs::path(config_.out) / "eval").string();
  ec.scoring.lpips = {};  // the report reads scores; it computes none
  Evaluator ev(ec);
  const std::string lp = "squeeze";  // the LPIPS variant reported (the one with real weights here)

  std::ostringstream md;
  md << "# Ablation report\n\n"
     << "Every row is trained from the same recipe (`" << config_.train_config
     << "`) and scored on the same pairs with "
     << "the same masks. Delta = row minus `" << config_.reference
     << "` on the same pairs (its seeds averaged per pair), with a paired bootstrap 95% interval (" << config_.bootstrap
     << " resamples); an interval that contains 0 is no difference.\n\n";
  CsvTable csv;
  csv.header = {"dataset",
                "variant",
                "row",
                "bin",
                "pairs",
                "psnr",
                "ssim",
                "lpips_" + lp,
                "delta_psnr",
                "delta_psnr_lo",
                "delta_psnr_hi",
                "delta_lpips",
                "delta_lpips_lo",
                "delta_lpips_hi",
                "holes_pct",
                "cracks_pct",
                "normals_deg",
                "delta_holes",
                "delta_holes_lo",
                "delta_holes_hi",
                "delta_cracks",
                "delta_cracks_lo",
                "delta_cracks_hi",
                "interval"};
  nlohmann::ordered_json js = nlohmann::ordered_json::array();
  std::vector<Chart> delta_charts;

  for (size_t d = 0; d < ec.datasets.size(); ++d) {
    const auto& ds = ec.datasets[d];
    const std::string manifest_path = (fs::path(ev.dataset_dir(d)) / "manifest.json").string();
    if (!fs::exists(manifest_path)) {
      md << "## " << ds.name << "\n\nNot evaluated yet (no " << manifest_path << ").\n\n";
      continue;
    }
    const Manifest m = read_manifest(manifest_path);
    const std::vector<int64_t> pairs = ev.select_pairs(m);
    std::vector<std::string> bins;
    for (size_t b = 0; b < m.bin_counts.size(); ++b) bins.push_back(m.bin_label(static_cast<int>(b)));
    std::vector<int> pair_bin;
    for (int64_t i : pairs) pair_bin.push_back(m.pairs[static_cast<size_t>(i)].bin);
    auto load = [&](const std::string& method) {
      Scores s;
      const std::string path = ev.results_path(d, method);
      if (!fs::exists(path)) return s;
      const ResultsLog log(path, [&](const PairResult& r) { return check_against_manifest(r, m); });
      for (int64_t i : pairs) {
        auto it = log.done().find(i);
        const bool ok = it != log.done().end();
        s.any |= ok;
        s.psnr.push_back(ok ? it->second.psnr : NAN);
        s.ssim.push_back(ok ? it->second.ssim : NAN);
        const double l = ok && it->second.lpips.count(lp) ? it->second.lpips.at(lp) : NAN;
        s.lpips.push_back(l);
        s.holes.push_back(ok ? 100 * it->second.hole_rate : NAN);
        s.cracks.push_back(ok ? 100 * it->second.crack_rate : NAN);
        s.normals.push_back(ok ? it->second.normal_deg : NAN);
      }
      return s;
    };
    auto subset = [&](const std::vector<double>& v, int bin) { return in_bin(v, pair_bin, bin); };
    md << "## " << ds.name << " (" << pairs.size() << " pairs; per bin:";
    for (size_t b = 0; b < bins.size(); ++b) md << " " << bins[b] << " " << m.bin_counts[b];
    md << ")\n\n";

    for (const auto& v : config_.variants) {
      // Reference: the reference row's seeds, averaged per pair.
      const ExperimentRow& ref_row = row(config_.reference);
      std::vector<Scores> ref_seeds;
      std::map<int64_t, Scores> ref_by_seed;
      for (const auto& run : runs(ref_row)) {
        Scores s = load(method_name(ref_row, run.seed, v));
        if (s.any) ref_seeds.push_back(s), ref_by_seed[run.seed] = s;
      }
      if (ref_seeds.empty()) {
        md << "### " << v.name << "\n\nThe reference row `" << config_.reference
           << "` is not scored in this variant yet.\n\n";
        continue;
      }
      Scores ref;
      ref.any = true;
      for (size_t k = 0; k < pairs.size(); ++k) {
        auto avg = [&](auto member) {
          double sum = 0;
          int n = 0;
          for (const auto& s : ref_seeds)
            if (std::isfinite((s.*member)[k])) sum += (s.*member)[k], ++n;
          return n == static_cast<int>(ref_seeds.size()) ? sum / n : NAN;
        };
        ref.psnr.push_back(avg(&Scores::psnr));
        ref.ssim.push_back(avg(&Scores::ssim));
        ref.lpips.push_back(avg(&Scores::lpips));
        ref.holes.push_back(avg(&Scores::holes));
        ref.cracks.push_back(avg(&Scores::cracks));
        ref.normals.push_back(avg(&Scores::normals));
      }
      md << "### " << v.name << (v.overrides.empty() ? "" : " (model overrides: ");
      for (size_t k = 0; k < v.overrides.size(); ++k) md << (k ? ", " : "") << "`" << v.overrides[k] << "`";
      md << (v.overrides.empty() ? "" : ")") << "\n\n| row | PSNR | SSIM | LPIPS (" << lp
         << ") | ΔPSNR [95% CI] | ΔLPIPS [95% CI] |";
      for (const auto& b : bins) md << " " << b << " PSNR (Δ [CI]) |";
      md << "\n|---|---|---|---|---|---|";
      for (size_t b = 0; b < bins.size(); ++b) md << "---|";
      md << "\n";

      // Where single-image methods fail: holes and cracks, overall and at the largest baselines.
      const int last_bin = static_cast<int>(bins.size()) - 1;
      std::ostringstream stab;
      stab << "Stability (holes: masked pixels with rendered alpha < 0.5; cracks: neighbours whose rendered depth "
              "jumps where the reference is smooth; normals: mean angle between neighbouring rendered normals on "
              "reference-planar surfaces). Δ to `"
           << config_.reference << "` with a paired 95% interval:\n\n| row | holes % | cracks % | normals deg | "
           << bins[static_cast<size_t>(last_bin)] << " holes % (Δ [CI]) | " << bins[static_cast<size_t>(last_bin)]
           << " cracks % (Δ [CI]) |\n|---|---|---|---|---|---|\n";
      bool any_stability = false;
      std::vector<std::string> unmeasured;  // rows scored before the stability measures existed

      Chart chart;
      chart.title = cat(ds.name, " / ", v.name, ": PSNR minus ", config_.reference, " per baseline bin");
      chart.x_label = "baseline bin (0 = smallest)";
      chart.y_label = "delta PSNR (dB), mean over the bin's pairs";
      // Rows: every trained row and seed, then the baselines.
      struct Entry {
        std::string name, label;
        Scores s;
        bool is_ref_seed = false, is_baseline = false;
      };
      std::vector<Entry> entries;
      for (const auto& r : config_.rows) {
        if (!v.rows.empty() && !wanted(v.rows, r.name)) continue;
        for (const auto& run : runs(r)) {
          const std::string name = method_name(r, run.seed, v);
          Scores s = load(name);
          if (!s.any) continue;
          entries.push_back({name, r.label.empty() ? r.name : r.label, s, r.name == config_.reference});
        }
      }
      for (const auto& b : config_.baselines) {
        Scores s = load(b);
        if (s.any) entries.push_back({b, b, s, false, true});
      }
      if (ref_seeds.size() > 1) {  // training noise: the reference's seeds against each other
        entries.push_back(
            {cat(config_.reference, " seed spread"), "seed 1 - seed 0 of the reference", ref_seeds[1], false});
      }
      for (size_t k = 0; k < entries.size(); ++k) {
        const Entry& e = entries[k];
        const bool spread = e.name.find("seed spread") != std::string::npos;
        const Scores& base = spread ? ref_seeds[0] : ref;
        const Interval dp = paired_bootstrap(e.s.psnr, base.psnr, config_.bootstrap);
        const Interval dl = paired_bootstrap(e.s.lpips, base.lpips, config_.bootstrap);
        const bool self = e.is_ref_seed && ref_seeds.size() == 1;
        md << "| " << e.name << (e.label != e.name ? " (" + e.label + ")" : "") << " | "
           << fmt(mean_finite(e.s.psnr), 2) << " | " << fmt(mean_finite(e.s.ssim), 3) << " | "
           << fmt(mean_finite(e.s.lpips), 3) << " | " << (self ? "reference" : interval_fmt(dp, 2)) << " | "
           << (self ? "reference" : interval_fmt(dl, 3)) << " |";
        ChartSeries series;
        series.name = e.name;
        series.marker = static_cast<int>(k % 4);
        // Stability of one bin (-1 = all pairs): the row's means and its paired differences to the reference.
        struct Stability {
          double holes, cracks, normals;
          Interval dh, dc;
        };
        auto stability = [&](int bin) {
          return Stability{mean_finite(subset(e.s.holes, bin)), mean_finite(subset(e.s.cracks, bin)),
                           mean_finite(subset(e.s.normals, bin)),
                           paired_bootstrap(subset(e.s.holes, bin), subset(base.holes, bin), config_.bootstrap),
                           paired_bootstrap(subset(e.s.cracks, bin), subset(base.cracks, bin), config_.bootstrap)};
        };
        std::vector<Stability> stability_of;  // [0]: all pairs, [b + 1]: bin b
        for (int b = -1; b <= last_bin; ++b) stability_of.push_back(stability(b));
        const Stability &all = stability_of.front(), &far = stability_of.back();
        if (!std::isfinite(all.holes)) {
          unmeasured.push_back(e.name);
        } else {
          any_stability = true;
          stab << "| " << e.name << " | " << fmt(all.holes, 2) << " | " << fmt(all.cracks, 2) << " | "
               << fmt(all.normals, 1) << " | " << fmt(far.holes, 2)
               << (self || far.dh.n == 0 ? std::string() : " (" + interval_fmt(far.dh, 2) + ")") << " | "
               << fmt(far.cracks, 2) << (self || far.dc.n == 0 ? std::string() : " (" + interval_fmt(far.dc, 2) + ")")
               << " |\n";
        }
        auto add_csv = [&](const std::string& bin, const std::vector<double>& p, const std::vector<double>& s,
                           const std::vector<double>& l, const Interval& ip, const Interval& il, const Stability& st) {
          TableRow t;
          t.row = e.name, t.label = e.label, t.bin = bin;
          for (double x : p) t.pairs += std::isfinite(x);
          t.psnr = mean_finite(p), t.ssim = mean_finite(s), t.lpips = mean_finite(l);
          t.holes = st.holes, t.cracks = st.cracks, t.normals = st.normals;
          t.dp = ip, t.dl = il, t.dh = st.dh, t.dc = st.dc;
          t.interval = "pairs";
          add_table_row(csv, js, ds.name, v.name, config_.reference, lp, t);
        };
        add_csv("all", e.s.psnr, e.s.ssim, e.s.lpips, dp, dl, all);
        for (size_t b = 0; b < bins.size(); ++b) {
          const int bi = static_cast<int>(b);
          const auto p = subset(e.s.psnr, bi);
          const Interval bp = paired_bootstrap(p, subset(base.psnr, bi), config_.bootstrap);
          const Interval bl = paired_bootstrap(subset(e.s.lpips, bi), subset(base.lpips, bi), config_.bootstrap);
          md << " " << fmt(mean_finite(p), 2);
          if (!self && bp.n > 0) md << " (" << interval_fmt(bp, 2) << ")";
          md << " |";
          add_csv(bins[b], p, subset(e.s.ssim, bi), subset(e.s.lpips, bi), bp, bl, stability_of[b + 1]);
          series.x.push_back(static_cast<double>(b));
          series.y.push_back(self ? 0.0 : bp.mean);
        }
        md << "\n";
        // Baselines sit many dB away and would squash the rows' differences: they stay in the tables.
        if (!self && !spread && !e.is_baseline) chart.series.push_back(series);
      }
      md << "\n";
      if (any_stability) md << stab.str() << "\n";
      // Rows over their training seeds, seed k against the reference's seed k: the intervals resample seeds as
      // well as pairs, so they hold training noise, which the per-run intervals above leave out.
      // The runs' scores are those of `entries` (loaded above), not read again.
      auto scored = [&](const std::string& name) -> const Scores* {
        for (const Entry& e : entries)
          if (!e.is_baseline && e.name == name) return &e.s;
        return nullptr;
      };
      std::ostringstream by_seed;
      for (const auto& r : config_.rows) {
        if (r.name == config_.reference || (!v.rows.empty() && !wanted(v.rows, r.name))) continue;
        std::vector<Scores> mine, theirs;
        std::string seeds;
        std::vector<int64_t> seed_ids;
        for (const auto& run : runs(r)) {
          const auto it = ref_by_seed.find(run.seed);
          const Scores* s = it == ref_by_seed.end() ? nullptr : scored(method_name(r, run.seed, v));
          if (s == nullptr) continue;
          mine.push_back(*s), theirs.push_back(it->second);
          seeds += cat(seeds.empty() ? "" : "+", run.seed);
          seed_ids.push_back(run.seed);
        }
        if (mine.size() < 2) continue;
        const std::string name = cat(r.name, "@", v.name, " seeds ", seeds);
        const TableRow all = over_seeds(mine, theirs, pair_bin, -1, config_.bootstrap);
        const TableRow far = over_seeds(mine, theirs, pair_bin, last_bin, config_.bootstrap);
        by_seed << "| " << name << " | " << fmt(all.psnr, 2) << " | " << interval_fmt(all.dp, 2) << " | "
                << interval_fmt(all.dl, 3) << " | " << (far.dh.n ? interval_fmt(far.dh, 2) : "n/a") << " | "
                << (far.dc.n ? interval_fmt(far.dc, 2) : "n/a") << " |";
        // Each seed against its own reference seed, so a reader sees whether the seeds agree in sign.
        for (size_t k = 0; k < mine.size(); ++k) {
          auto delta = [&](std::vector<double> Scores::*m, int bin) {  // the paired mean difference
            return paired_bootstrap(in_bin(mine[k].*m, pair_bin, bin), in_bin(theirs[k].*m, pair_bin, bin), 1).mean;
          };
          by_seed << (k ? "; " : " ") << "s" << seed_ids[k] << " " << signed_fmt(delta(&Scores::psnr, -1), 2) << " / "
                  << signed_fmt(delta(&Scores::holes, last_bin), 2) << " / "
                  << signed_fmt(delta(&Scores::cracks, last_bin), 2);
        }
        by_seed << " |\n";
        for (int b = -1; b <= last_bin; ++b) {
          TableRow t = b < 0 ? all : b == last_bin ? far : over_seeds(mine, theirs, pair_bin, b, config_.bootstrap);
          t.row = name, t.label = r.label.empty() ? r.name : r.label;
          t.bin = b < 0 ? "all" : bins[static_cast<size_t>(b)];
          add_table_row(csv, js, ds.name, v.name, config_.reference, lp, t);
        }
      }
      if (!by_seed.str().empty()) {
        md << "Rows over their training seeds: seed k of a row against seed k of `" << config_.reference
           << "`, averaged over the seeds both have; the interval resamples the seeds as well as the pairs, so it "
              "holds training noise, which the per-run rows above leave out. With two seeds it is crude (a "
              "bootstrap of two seeds understates their spread):\n\n"
              "| row | PSNR | ΔPSNR [95% CI] | ΔLPIPS [95% CI] | "
           << bins[static_cast<size_t>(last_bin)] << " Δholes % [CI] | " << bins[static_cast<size_t>(last_bin)]
           << " Δcracks % [CI] | per seed: ΔPSNR / " << bins[static_cast<size_t>(last_bin)] << " Δholes / Δcracks |\n"
           << "|---|---|---|---|---|---|---|\n"
           << by_seed.str() << "\n";
      }
      if (any_stability && !unmeasured.empty()) {
        md << "Without holes and cracks (the method renders no alpha, like identity, or was scored before they were "
              "measured: delete its results_*.jsonl and stamp to score it again):";
        for (const auto& n : unmeasured) md << " " << n;
        md << ".\n\n";
      }
      delta_charts.push_back(chart);
    }
  }

  // Training curves of every run: loss and validation PSNR against step and against CPU time.
  Chart loss_step{"training loss (total) vs step", "step", "loss", false, {}};
  Chart val_step{"validation masked PSNR vs step", "step", "PSNR (dB)", false, {}};
  Chart loss_cpu{"training loss (total) vs CPU time", "CPU time (s)", "loss", false, {}};
  Chart val_cpu{"validation masked PSNR vs CPU time", "CPU time (s)", "PSNR (dB)", false, {}};
  md << "Report written by commit " << build_commit()
     << ".\n\n## Training runs\n\n| run | steps | mean step (ms) | CPU "
        "time (s) | final val PSNR (dB) | trained by commit |\n|---|---|---|---|---|---|\n";
  int color = 0;
  for (const auto& r : config_.rows) {
    if (!r.from.empty()) continue;
    for (const auto& run : runs(r)) {
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
      md << "| " << r.name << "_s" << run.seed << " | " << steps << " | " << fmt(timed ? step_ms / timed : NAN, 0)
         << " | " << fmt(cpu, 1) << " | " << fmt(last_val, 2) << " | " << trained_by(run.dir) << " |\n";
      ++color;
    }
  }
  md << "\nCharts: `curves.png` (training curves), `deltas.png` (ΔPSNR per baseline bin).\n";
  fs::create_directories(config_.out);
  write_charts((fs::path(config_.out) / "curves.png").string(), {loss_step, val_step, loss_cpu, val_cpu});
  write_charts((fs::path(config_.out) / "deltas.png").string(),
               delta_charts.empty() ? std::vector<Chart>{Chart{}} : delta_charts);
  write_file_atomic((fs::path(config_.out) / "report.md").string(), md.str());
  write_csv((fs::path(config_.out) / "report.csv").string(), csv);
  write_file_atomic((fs::path(config_.out) / "report.json").string(), js.dump(2) + "\n");
  log_info("experiment: report in ", config_.out, " (report.md, report.csv, report.json, curves.png, deltas.png)");
}

}  // namespace isplat

// Experiment::report(): report.md, report.csv, report.json, curves.png and deltas.png from the logged scores.
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "eval/evaluator.h"
#include "experiment/experiment.h"
#include "experiment/scores.h"
#include "io/atomic_file.h"
#include "io/chart.h"
#include "io/jsonl.h"
#include "io/table.h"
#include "metrics/stats.h"

namespace isplat {
namespace fs = std::filesystem;
using ablation::add_result;
using ablation::dataset_scores;
using ablation::DatasetScores;
using ablation::in_bin;
using ablation::interval_fmt;
using ablation::on_bin;
using ablation::over_seeds;
using ablation::results_table;
using ablation::Scores;
using ablation::signed_fmt;
using ablation::TableRow;
using ablation::wanted;

namespace {
// The commit a finished run's summary names ("not recorded" for runs finished before commits were recorded).
std::string trained_by(const std::string& run_dir) {
  const fs::path summary = fs::path(run_dir) / "summary.json";
  if (!fs::exists(summary)) return "not finished";
  const nlohmann::json s = read_json_file(summary.string());
  return s.contains("commit") && s["commit"].is_string() ? s["commit"].get<std::string>() : "not recorded";
}

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

// The experiment's scores on its pairs and report rows from them: means with paired or seed-aware intervals.
#include "experiment/scores.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>

#include "core/error.h"
#include "eval/evaluator.h"
#include "eval/results_log.h"

namespace isplat {
namespace ablation {
namespace fs = std::filesystem;

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

// `v` with the pairs outside baseline bin `bin` set to NaN (bin < 0: all pairs).
std::vector<double> in_bin(const std::vector<double>& v, const std::vector<int>& pair_bin, int bin) {
  if (bin < 0) return v;
  std::vector<double> out;
  for (size_t k = 0; k < v.size(); ++k) out.push_back(pair_bin[k] == bin ? v[k] : NAN);
  return out;
}

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

}  // namespace ablation
}  // namespace isplat

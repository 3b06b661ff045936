// Internal to the experiment: a method's scores on the experiment's pairs and the report rows made from them.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "io/table.h"
#include "metrics/stats.h"

namespace isplat {

class Evaluator;
struct EvalConfig;

namespace ablation {

// Whether `name` is selected: listed in `only`, or `only` is empty.
inline bool wanted(const std::vector<std::string>& only, const std::string& name) {
  return only.empty() || std::find(only.begin(), only.end(), name) != only.end();
}

std::string signed_fmt(double v, int digits);             // "+0.12"
std::string interval_fmt(const Interval& i, int digits);  // "+0.12 [+0.05, +0.20]"
double mean_finite(const std::vector<double>& v);         // over the finite values; NaN when none

// One scored method's values on the experiment's pair list (NaN where not scored).
struct Scores {
  std::vector<double> psnr, ssim, lpips;
  std::vector<double> holes, cracks, normals;  // stability measures in % and degrees (NaN where not measured)
  bool any = false;
};

// `v` with the pairs outside baseline bin `bin` set to NaN (bin < 0: all pairs).
std::vector<double> in_bin(const std::vector<double>& v, const std::vector<int>& pair_bin, int bin);

// One row of report.csv / report.json: a row's means on one bin and its differences to the reference.
struct TableRow {
  std::string row, label, bin;
  int64_t pairs = 0;
  double psnr = NAN, ssim = NAN, lpips = NAN, holes = NAN, cracks = NAN, normals = NAN;
  Interval dp, dl, dh, dc;  // PSNR, LPIPS, holes, cracks minus the reference
  std::string interval;     // what the intervals resample: "pairs" or "seeds and pairs"
};

// report.csv and report.json: the columns, declared once.
Table results_table(const std::string& lp);
// Appends one row to report.csv / report.json's table.
void add_result(Table& table, const std::string& dataset, const std::string& variant, const std::string& reference,
                const TableRow& t);

// One run's (or baseline's) scores against `base` on one bin (-1 = all pairs): means and paired intervals.
TableRow on_bin(const Scores& s, const Scores& base, const std::vector<int>& pair_bin, int bin, int64_t resamples);
// A row over its training seeds against the reference's same seeds (mine[k] and ref[k] share seed k) on one bin:
// means over the seeds, and seed-aware intervals (seed_paired_bootstrap).
TableRow over_seeds(const std::vector<Scores>& mine, const std::vector<Scores>& ref, const std::vector<int>& pair_bin,
                    int bin, int64_t resamples);

// One dataset's scores on the experiment's pairs: what every variant's tables read.
struct DatasetScores {
  std::string name;
  std::vector<std::string> bins;
  std::vector<int64_t> bin_counts;
  std::vector<int> pair_bin;                       // each pair's baseline bin
  std::function<Scores(const std::string&)> load;  // a scored method's values (none when it has no results)
};

// The scores of dataset d on the experiment's pairs, or nothing when it was not evaluated yet.
std::optional<DatasetScores> dataset_scores(const Evaluator& ev, const EvalConfig& ec, size_t d, const std::string& lp);

}  // namespace ablation
}  // namespace isplat

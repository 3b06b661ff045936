// Statistics for comparing methods on the same evaluation pairs: means and paired bootstrap intervals.
#pragma once
#include <cstdint>
#include <vector>

namespace isplat {

struct Interval {
  double mean = 0;        // mean of the paired differences
  double lo = 0, hi = 0;  // percentile bootstrap interval
  int64_t n = 0;          // pairs used (both values finite)
  bool excludes_zero() const { return n > 0 && (lo > 0 || hi < 0); }
};

// Paired bootstrap of mean(a_i - b_i) over the pairs where both are finite: `resamples` draws of n pairs
// with replacement (seeded, deterministic), and the (1-level)/2 and (1+level)/2 percentiles of the
// resampled means (nearest-rank). a and b must have the same length (same pairs, same order).
Interval paired_bootstrap(const std::vector<double>& a, const std::vector<double>& b, int64_t resamples = 2000,
                          double level = 0.95, uint64_t seed = 0);

// Seed-aware paired bootstrap of mean(a - b) when both methods were trained with several seeds: a[k] and b[k] are
// training seed k's per-pair values (seed k of one against seed k of the other, which share initialisation and data
// order; every seed over the same pairs in the same order). Each resample draws the seeds with replacement, then
// the pairs, and averages a - b over both draws, so the interval holds training noise as well as the pairs'
// spread. Pairs where any seed of either method is not finite are dropped. Needs at least one seed.
Interval seed_paired_bootstrap(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                               int64_t resamples = 2000, double level = 0.95, uint64_t seed = 0);

}  // namespace isplat

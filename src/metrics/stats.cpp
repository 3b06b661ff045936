// Paired percentile bootstrap with a fixed-seed generator, so reports are reproducible.
#include "metrics/stats.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace isplat {
namespace {

// The (1-level)/2 and (1+level)/2 nearest-rank percentiles of the resampled means as out.lo and out.hi.
Interval with_percentiles(Interval out, std::vector<double>& means, double level) {
  std::sort(means.begin(), means.end());
  const auto resamples = static_cast<int64_t>(means.size());
  auto rank = [&](double q) {
    const auto k = static_cast<int64_t>(std::ceil(q * resamples)) - 1;
    return means[static_cast<size_t>(std::clamp<int64_t>(k, 0, resamples - 1))];
  };
  out.lo = rank((1 - level) / 2);
  out.hi = rank((1 + level) / 2);
  return out;
}

}  // namespace

Interval paired_bootstrap(const std::vector<double>& a, const std::vector<double>& b, int64_t resamples, double level,
                          uint64_t seed) {
  ISPLAT_CHECK(a.size() == b.size(), "paired_bootstrap: ", a.size(), " and ", b.size(), " values are not paired");
  ISPLAT_CHECK(resamples > 0 && level > 0 && level < 1, "paired_bootstrap: resamples ", resamples, ", level ", level);
  std::vector<double> d;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::isfinite(a[i]) && std::isfinite(b[i])) d.push_back(a[i] - b[i]);
  Interval out;
  out.n = static_cast<int64_t>(d.size());
  if (d.empty()) {
    out.mean = out.lo = out.hi = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  double sum = 0;
  for (double x : d) sum += x;
  out.mean = sum / d.size();
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, d.size() - 1);
  std::vector<double> means(static_cast<size_t>(resamples));
  for (auto& m : means) {
    double s = 0;
    for (size_t k = 0; k < d.size(); ++k) s += d[pick(rng)];
    m = s / d.size();
  }
  return with_percentiles(out, means, level);
}

Interval seed_paired_bootstrap(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                               int64_t resamples, double level, uint64_t seed) {
  ISPLAT_CHECK(!a.empty() && a.size() == b.size(), "seed_paired_bootstrap: ", a.size(), " and ", b.size(),
               " seeds (need the same number, at least one)");
  ISPLAT_CHECK(resamples > 0 && level > 0 && level < 1, "seed_paired_bootstrap: resamples ", resamples, ", level ",
               level);
  const size_t seeds = a.size(), pairs = a[0].size();
  for (size_t k = 0; k < seeds; ++k)
    ISPLAT_CHECK(a[k].size() == pairs && b[k].size() == pairs, "seed_paired_bootstrap: seed ", k, " has ", a[k].size(),
                 " and ", b[k].size(), " values, seed 0 has ", pairs);
  std::vector<size_t> kept;  // pairs finite in every seed of both
  for (size_t i = 0; i < pairs; ++i) {
    bool ok = true;
    for (size_t k = 0; k < seeds && ok; ++k) ok = std::isfinite(a[k][i]) && std::isfinite(b[k][i]);
    if (ok) kept.push_back(i);
  }
  Interval out;
  out.n = static_cast<int64_t>(kept.size());
  if (kept.empty()) {
    out.mean = out.lo = out.hi = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  std::vector<std::vector<double>> d(seeds);  // d[k][j]: seed k's difference on kept pair j
  double sum = 0;
  for (size_t k = 0; k < seeds; ++k)
    for (size_t i : kept) d[k].push_back(a[k][i] - b[k][i]), sum += d[k].back();
  out.mean = sum / double(seeds * kept.size());
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick_seed(0, seeds - 1), pick_pair(0, kept.size() - 1);
  std::vector<size_t> drawn_seeds(seeds), drawn_pairs(kept.size());
  std::vector<double> means(static_cast<size_t>(resamples));
  for (auto& m : means) {
    for (auto& k : drawn_seeds) k = pick_seed(rng);
    for (auto& j : drawn_pairs) j = pick_pair(rng);
    double s = 0;
    for (size_t k : drawn_seeds)
      for (size_t j : drawn_pairs) s += d[k][j];
    m = s / double(seeds * kept.size());
  }
  return with_percentiles(out, means, level);
}

}  // namespace isplat

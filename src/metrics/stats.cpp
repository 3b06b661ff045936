// Paired percentile bootstrap with a fixed-seed generator, so reports are reproducible.
#include "metrics/stats.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace isplat {

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
  std::sort(means.begin(), means.end());
  auto rank = [&](double q) {  // nearest-rank percentile
    const auto k = static_cast<int64_t>(std::ceil(q * resamples)) - 1;
    return means[static_cast<size_t>(std::clamp<int64_t>(k, 0, resamples - 1))];
  };
  out.lo = rank((1 - level) / 2);
  out.hi = rank((1 + level) / 2);
  return out;
}

}  // namespace isplat

// Aggregation: pair results into report rows (per bin and finer groups), paired differences and sweep slopes.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>

#include "core/error.h"
#include "eval/depth_eval.h"
#include "eval/report.h"
#include "eval/report_parts.h"

namespace isplat {
namespace reporting {

// A value sweep's point on dataset d over all bins (budgets are not value sweeps).
bool is_sweep_point(const ReportRow& r, const std::string& d) {
  return r.dataset == d && r.bin == "all" && !r.method.sweep.key.empty() && std::isfinite(r.method.sweep.value);
}

// The value sweeps on dataset d ("full depth_noise"), each as its first point, in the order they first appear.
std::vector<MethodId> sweep_families(const std::vector<ReportRow>& rows, const std::string& d) {
  std::vector<MethodId> families;
  for (const auto& r : rows)
    if (is_sweep_point(r, d) && std::none_of(families.begin(), families.end(),
                                             [&](const MethodId& f) { return f.family() == r.method.family(); }))
      families.push_back(r.method);
  return families;
}

// Each perturbation's value that changes nothing (scale and exposure 1, the others 0).
const std::map<std::string, double>& neutral_values() {
  static const std::map<std::string, double> neutral = {
      {"depth_scale", 1}, {"exposure", 1},         {"depth_noise", 0},     {"depth_blur_px", 0},
      {"depth_holes", 0}, {"depth_edge_noise", 0}, {"depth_hole_size", 0}, {"depth_edge_holes", 0}};
  return neutral;
}

// A sweep's points (value, field) on dataset d, all bins. When the sweep leaves out the unperturbed value of
// a perturbation (scale and exposure 1, the others 0) and the same method runs unperturbed (the family's
// name without a sweep), that run is the point there.
std::vector<std::pair<double, double>> sweep_points(const std::vector<ReportRow>& rows, const std::string& d,
                                                    const MethodId& family, double ReportRow::*field, double scale) {
  const std::map<std::string, double>& neutral = neutral_values();
  std::vector<std::pair<double, double>> pts;
  for (const auto& r : rows)
    if (is_sweep_point(r, d) && r.method.family() == family.family())
      pts.push_back({r.method.sweep.value, scale * (r.*field)});
  const auto it = neutral.find(family.sweep.axis());
  if (it != neutral.end() && std::none_of(pts.begin(), pts.end(), [&](auto& p) { return p.first == it->second; }))
    for (const auto& r : rows)
      if (r.dataset == d && r.bin == "all" && r.method == MethodId{family.name, {}})
        pts.push_back({it->second, scale * (r.*field)});
  std::sort(pts.begin(), pts.end());
  return pts;
}

// How strong a perturbation of `key` is at a swept value (0 = none), and the unit of that strength.
std::pair<std::function<double(double)>, std::string> perturbation_strength(const std::string& key) {
  if (key.find("noise") != std::string::npos || key == "depth_holes") return {[](double v) { return 100 * v; }, "%"};
  if (key == "depth_scale" || key == "exposure")
    return {[](double v) { return std::abs(std::log(v)); }, "unit of abs(ln value)"};
  if (key == "jpeg_quality") return {[](double v) { return 100 - v; }, "quality point lost"};
  if (key == "prompts") return {[](double v) { return -std::log(v); }, "e-fold fewer"};
  return {[](double v) { return v; }, key == "depth_blur_px" || key == "depth_edge_holes" ? "pixel" : "unit"};
}

}  // namespace reporting

using reporting::neutral_values;
using reporting::perturbation_strength;

// Each field's mean over the scores where it is finite (NaN where none is).
static RegionScore mean_score(const std::vector<const RegionScore*>& scores) {
  RegionScore mean;
  for (double RegionScore::*field :
       {&RegionScore::share, &RegionScore::psnr, &RegionScore::lpips, &RegionScore::detail, &RegionScore::density}) {
    double sum = 0;
    int64_t n = 0;
    for (const RegionScore* g : scores)
      if (std::isfinite(g->*field)) sum += g->*field, ++n;
    mean.*field = n ? sum / double(n) : std::numeric_limits<double>::quiet_NaN();
  }
  return mean;
}

std::vector<ReportRow> summarize(const std::string& dataset, const MethodId& method,
                                 const std::vector<std::string>& bin_labels, const std::vector<int64_t>& requested,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets) {
  std::vector<ReportRow> rows;
  auto make = [&](const std::string& label, int bin, int64_t req) {
    ReportRow r;
    r.dataset = dataset;
    r.method = method;
    r.bin = label;
    r.requested = req;
    double p = 0, s = 0, inf = 0, ren = 0, g = 0, dec = 0;
    double stab[3] = {0, 0, 0};
    int64_t stab_n[3] = {0, 0, 0};
    std::map<std::string, double> stage, pruned;
    int64_t pruned_n = 0;
    r.peak_mb = r.work_mb = std::numeric_limits<double>::quiet_NaN();
    std::map<std::string, double> lp;
    std::map<std::string, int64_t> lp_n;
    int64_t psnr_n = 0;
    std::map<double, DisplayScore> display_sum;
    std::map<double, std::pair<int64_t, int64_t>> display_n;  // pairs with a finite PSNR, with a hole rate
    std::vector<double> scales;
    DensifyScore dense_sum[2] = {{0, 0, 0}, {0, 0, 0}};
    std::map<std::string, std::vector<const RegionScore*>> regions;
    for (const auto& x : results) {
      if (bin >= 0 && x.bin != bin) continue;
      ++r.pairs;
      for (const auto& [name, g] : x.regions) regions[name].push_back(&g);
      if (std::isfinite(x.source_view.share)) regions["source_view"].push_back(&x.source_view);
      if (std::isfinite(x.psnr)) p += x.psnr, ++psnr_n;
      s += x.ssim, inf += x.infer_ms, ren += x.render_ms, g += x.gaussians, dec += x.decoded;
      for (const auto& [k, v] : x.stage_ms) stage[k] += v;
      for (const DisplayScore& d : x.display) {
        DisplayScore& sum = display_sum[d.factor];
        auto& [np, nh] = display_n[d.factor];
        if (np == 0 && nh == 0) sum = {d.factor, 0.0, 0.0};
        if (std::isfinite(d.psnr)) sum.psnr += d.psnr, ++np;
        if (std::isfinite(d.hole_rate)) sum.hole_rate += d.hole_rate, ++nh;
      }
      if (std::isfinite(x.scale)) {
        if (x.scale_samples > 0)
          scales.push_back(x.scale);
        else
          ++r.scale_missed;
      }
      const DensifyScore* dense[2] = {&x.unprompted, &x.removed};
      for (int k = 0; k < 2; ++k)
        if (dense[k]->pixels > 0 && std::isfinite(dense[k]->abs_rel))
          dense_sum[k].abs_rel += dense[k]->abs_rel, dense_sum[k].delta1 += dense[k]->delta1, ++dense_sum[k].pixels;
      for (const auto& [k, v] : x.prune_counts) pruned[k] += double(v);
      pruned_n += x.prune_counts.empty() ? 0 : 1;
      const double measures[3] = {x.hole_rate, x.crack_rate, x.normal_deg};
      for (int k = 0; k < 3; ++k)
        if (std::isfinite(measures[k])) stab[k] += measures[k], ++stab_n[k];
      if (std::isfinite(x.peak_mb)) r.peak_mb = std::isfinite(r.peak_mb) ? std::max(r.peak_mb, x.peak_mb) : x.peak_mb;
      if (std::isfinite(x.work_mb)) r.work_mb = std::isfinite(r.work_mb) ? std::max(r.work_mb, x.work_mb) : x.work_mb;
      for (const auto& net : lpips_nets) {
        auto it = x.lpips.find(net);
        if (it != x.lpips.end() && std::isfinite(it->second)) lp[net] += it->second, ++lp_n[net];
      }
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double n = static_cast<double>(r.pairs);
    r.psnr = psnr_n ? p / psnr_n : nan;
    r.ssim = r.pairs ? s / n : nan;
    r.infer_ms = r.pairs ? inf / n : nan;
    r.render_ms = r.pairs ? ren / n : nan;
    r.gaussians = r.pairs ? g / n : nan;
    r.decoded = r.pairs ? dec / n : nan;
    for (const auto& [k, v] : stage) r.stage_ms[k] = v / n;
    for (const auto& [k, v] : pruned) r.prune_counts[k] = v / double(pruned_n);
    double* outs[3] = {&r.hole_rate, &r.crack_rate, &r.normal_deg};
    for (int k = 0; k < 3; ++k) *outs[k] = stab_n[k] ? stab[k] / static_cast<double>(stab_n[k]) : nan;
    for (const auto& net : lpips_nets) r.lpips[net] = lp_n[net] ? lp[net] / lp_n[net] : nan;
    for (const auto& [factor, sum] : display_sum) {
      const auto [np, nh] = display_n[factor];
      r.display[factor] = {factor, np ? sum.psnr / np : nan, nh ? sum.hole_rate / nh : nan};
    }
    r.scale_pairs = static_cast<int64_t>(scales.size());
    if (!scales.empty()) {
      const ScaleSummary sc = summarize_scales(scales);
      r.scale = sc.mean, r.scale_spread = sc.spread;
    }
    DensifyScore* dense_out[2] = {&r.unprompted, &r.removed};
    for (int k = 0; k < 2; ++k)
      if (const int64_t m = dense_sum[k].pixels; m > 0)
        *dense_out[k] = {dense_sum[k].abs_rel / double(m), dense_sum[k].delta1 / double(m), m};
    for (const auto& [name, scores] : regions) r.regions[name] = mean_score(scores);
    rows.push_back(r);
  };
  int64_t total_req = 0;
  for (size_t b = 0; b < bin_labels.size(); ++b) {
    make(bin_labels[b], static_cast<int>(b), requested[b]);
    total_req += requested[b];
  }
  make("all", -1, total_req);
  return rows;
}

std::vector<ReportRow> breakdown(const std::string& dataset, const MethodId& method,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets,
                                 double step_m) {
  ISPLAT_CHECK(step_m > 0 && std::isfinite(step_m), "breakdown: baseline step ", step_m, " is not positive");
  std::vector<ReportRow> out;
  auto keep = [&](std::vector<ReportRow> rows, const std::string& prefix) {
    for (auto& r : rows)
      if (r.bin != "all" && r.pairs > 0) r.bin = prefix + r.bin, out.push_back(std::move(r));
  };
  double largest = 0;
  for (const auto& x : results) largest = std::max(largest, x.baseline);
  const int groups = static_cast<int>(std::floor(largest / step_m + 1e-9)) + 1;
  std::vector<PairResult> regrouped = results;
  // The epsilon keeps a baseline on an edge (0.3 with step 0.1) in the group it opens.
  for (auto& x : regrouped) x.bin = static_cast<int>(std::floor(x.baseline / step_m + 1e-9));
  std::vector<std::string> labels;
  for (int k = 0; k < groups; ++k) {
    labels.push_back(cat("[", k * step_m, ",", (k + 1) * step_m, ")"));
  }
  keep(summarize(dataset, method, labels, std::vector<int64_t>(labels.size(), 0), regrouped, lpips_nets), "baseline ");
  const std::vector<std::string> motions = {"lateral", "forward", "rotation"};
  regrouped = results;
  for (auto& x : regrouped)
    x.bin = static_cast<int>(std::find(motions.begin(), motions.end(), x.motion) - motions.begin());
  keep(summarize(dataset, method, motions, std::vector<int64_t>(motions.size(), 0), regrouped, lpips_nets), "motion ");
  return out;
}

std::vector<DiffRow> paired_differences(const std::string& dataset, const std::string& reference,
                                        const ScoredMethods& results, const std::string& lpips_net, int64_t resamples,
                                        const std::vector<std::string>& bin_labels) {
  std::vector<DiffRow> out;
  const auto ref =
      std::find_if(results.begin(), results.end(), [&](const auto& m) { return m.first.label() == reference; });
  if (ref == results.end()) return out;
  std::map<int64_t, const PairResult*> by_pair;
  for (const auto& r : ref->second) by_pair[r.index] = &r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto lp = [&](const PairResult& r) {
    const auto it = r.lpips.find(lpips_net);
    return it == r.lpips.end() ? nan : it->second;
  };
  for (const auto& [method, res] : results) {
    if (method.label() == reference) continue;
    for (int bin = -1; bin < static_cast<int>(bin_labels.size()); ++bin) {
      std::vector<double> a, b, la, lb, ha, hb, ca, cb;
      double ga = 0, gb = 0;
      for (const auto& r : res) {
        const auto it = by_pair.find(r.index);
        if (it == by_pair.end() || (bin >= 0 && r.bin != bin)) continue;
        const PairResult& q = *it->second;
        a.push_back(r.psnr), b.push_back(q.psnr), la.push_back(lp(r)), lb.push_back(lp(q));
        ha.push_back(100 * r.hole_rate), hb.push_back(100 * q.hole_rate);
        ca.push_back(100 * r.crack_rate), cb.push_back(100 * q.crack_rate);
        ga += static_cast<double>(r.gaussians), gb += static_cast<double>(q.gaussians);
      }
      if (a.empty()) continue;
      DiffRow d;
      d.dataset = dataset, d.method = method, d.reference = reference;
      d.psnr = paired_bootstrap(a, b, resamples);
      d.lpips = paired_bootstrap(la, lb, resamples);
      d.gaussians = gb > 0 ? ga / gb : nan;
      d.bin = bin < 0 ? "all" : bin_labels[static_cast<size_t>(bin)];
      d.holes = paired_bootstrap(ha, hb, resamples);
      d.cracks = paired_bootstrap(ca, cb, resamples);
      out.push_back(d);
    }
  }
  return out;
}

std::vector<SweepSlope> sweep_slopes(const std::string& dataset, const ScoredMethods& results, int64_t resamples) {
  const std::map<std::string, double>& neutral = neutral_values();
  std::map<std::string, std::vector<std::pair<double, const std::vector<PairResult>*>>> families;
  std::map<std::string, MethodId> first;  // each family's first point
  for (const auto& [method, res] : results)
    if (!method.sweep.key.empty() && std::isfinite(method.sweep.value)) {
      families[method.family()].push_back({method.sweep.value, &res});
      first.emplace(method.family(), method);
    }
  std::vector<SweepSlope> out;
  for (auto& [family, points] : families) {
    const std::string key = first.at(family).sweep.axis();
    // The unperturbed run stands for the neutral value when the sweep leaves it out (as sweep_points does).
    const auto it = neutral.find(key);
    const auto plain = results.find(MethodId{first.at(family).name, {}});
    if (it != neutral.end() && plain != results.end() &&
        std::none_of(points.begin(), points.end(), [&](auto& p) { return p.first == it->second; }))
      points.push_back({it->second, &plain->second});
    if (points.size() < 2) continue;
    const auto [strength, unit] = perturbation_strength(key);
    std::vector<double> xs;
    for (const auto& pt : points) xs.push_back(strength(pt.first));
    const double mx = std::accumulate(xs.begin(), xs.end(), 0.0) / static_cast<double>(xs.size());
    double sxx = 0;
    for (double x : xs) sxx += (x - mx) * (x - mx);
    if (!(sxx > 0)) continue;
    // Per pair: PSNR at every point (pairs some point missed are left out), then its slope.
    std::map<int64_t, std::vector<double>> by_pair;
    for (size_t k = 0; k < points.size(); ++k)
      for (const auto& r : *points[k].second) {
        auto& ys = by_pair[r.index];
        ys.resize(points.size(), std::numeric_limits<double>::quiet_NaN());
        ys[k] = r.psnr;
      }
    std::vector<double> slopes;
    for (const auto& [index, ys] : by_pair) {
      if (!std::all_of(ys.begin(), ys.end(), [](double y) { return std::isfinite(y); })) continue;
      const double my = std::accumulate(ys.begin(), ys.end(), 0.0) / static_cast<double>(ys.size());
      double sxy = 0;
      for (size_t k = 0; k < ys.size(); ++k) sxy += (xs[k] - mx) * (ys[k] - my);
      slopes.push_back(sxy / sxx);
    }
    if (slopes.empty()) continue;
    out.push_back(
        {dataset, family, unit, paired_bootstrap(slopes, std::vector<double>(slopes.size(), 0.0), resamples)});
  }
  return out;
}

}  // namespace isplat

// Aggregation and report writers (Markdown, CSV, JSON, PNG chart).
#include "eval/report.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <set>
#include <sstream>

#include "core/build_info.h"
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/chart.h"
#include "io/table.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
constexpr const char* kStages[] = {"prior", "sampler", "encoder", "decoder", "composer", "prune"};

}  // namespace

std::vector<size_t> pareto_front(const std::vector<std::pair<double, double>>& points) {
  std::vector<size_t> order(points.size()), front;
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return points[a].first < points[b].first ||
           (points[a].first == points[b].first && points[a].second > points[b].second);
  });
  double best = -std::numeric_limits<double>::infinity();
  for (size_t i : order)
    if (std::isfinite(points[i].first) && std::isfinite(points[i].second) && points[i].second > best)
      front.push_back(i), best = points[i].second;
  return front;
}

std::pair<int, int> family_style(size_t k) {
  static constexpr int kColors[] = {0, 1, 2, 3, 4, 5, 6, 8, 9};  // tab10 without the front's grey
  return {kColors[k % 9], static_cast<int>(k % 4)};
}

static std::vector<Chart> speed_quality_charts(const std::vector<ReportRow>& rows) {
  std::vector<std::string> datasets;
  for (const auto& r : rows)
    if (std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end()) datasets.push_back(r.dataset);
  std::vector<Chart> charts;
  for (const auto& d : datasets) {
    // One series per method family: full at budgets px 0.5 and px 2 are points of the series "full px".
    std::vector<std::string> families;
    std::vector<const ReportRow*> pts;
    for (const auto& r : rows) {
      if (r.dataset != d || r.bin != "all" || !std::isfinite(r.psnr)) continue;
      pts.push_back(&r);
      const std::string f = r.method.family();
      if (std::find(families.begin(), families.end(), f) == families.end()) families.push_back(f);
    }
    for (int axis = 0; axis < 2; ++axis) {
      Chart c;
      c.title = d + (axis == 0 ? ": quality against time" : ": quality against Gaussians");
      c.x_label = axis == 0 ? "inference + render per pair (ms)" : "Gaussians rendered";
      c.y_label = "masked PSNR (dB)";
      c.log_x = true;
      auto xval = [&](const ReportRow* r) { return axis == 0 ? r->infer_ms + r->render_ms : r->gaussians; };
      for (size_t k = 0; k < families.size(); ++k) {
        const auto [color, marker] = family_style(k);
        ChartSeries s{families[k], {}, {}, true, marker, color};
        std::vector<const ReportRow*> mine;
        for (const auto* r : pts)
          if (r->method.family() == families[k] && xval(r) > 0) mine.push_back(r);
        std::sort(mine.begin(), mine.end(), [&](auto* a, auto* b) { return xval(a) < xval(b); });
        for (const auto* r : mine) s.x.push_back(xval(r)), s.y.push_back(r->psnr);
        c.series.push_back(s);
      }
      std::vector<std::pair<double, double>> xy;
      for (const auto* r : pts)
        xy.push_back({xval(r) > 0 ? xval(r) : std::numeric_limits<double>::quiet_NaN(), r->psnr});
      ChartSeries front{"Pareto front", {}, {}, true, kParetoMarker, kParetoColor};
      for (size_t i : pareto_front(xy)) front.x.push_back(xy[i].first), front.y.push_back(xy[i].second);
      c.series.push_back(front);
      charts.push_back(c);
    }
  }
  return charts;
}

// A value sweep's point on dataset d over all bins (budgets are not value sweeps).
static bool is_sweep_point(const ReportRow& r, const std::string& d) {
  return r.dataset == d && r.bin == "all" && !r.method.sweep.key.empty() && std::isfinite(r.method.sweep.value);
}

// The value sweeps on dataset d ("full depth_noise"), each as its first point, in the order they first appear.
static std::vector<MethodId> sweep_families(const std::vector<ReportRow>& rows, const std::string& d) {
  std::vector<MethodId> families;
  for (const auto& r : rows)
    if (is_sweep_point(r, d) && std::none_of(families.begin(), families.end(),
                                             [&](const MethodId& f) { return f.family() == r.method.family(); }))
      families.push_back(r.method);
  return families;
}

// Each perturbation's value that changes nothing (scale and exposure 1, the others 0).
static const std::map<std::string, double>& neutral_values() {
  static const std::map<std::string, double> neutral = {
      {"depth_scale", 1}, {"exposure", 1},         {"depth_noise", 0},     {"depth_blur_px", 0},
      {"depth_holes", 0}, {"depth_edge_noise", 0}, {"depth_hole_size", 0}, {"depth_edge_holes", 0}};
  return neutral;
}

// A sweep's points (value, field) on dataset d, all bins. When the sweep leaves out the unperturbed value of
// a perturbation (scale and exposure 1, the others 0) and the same method runs unperturbed (the family's
// name without a sweep), that run is the point there.
static std::vector<std::pair<double, double>> sweep_points(const std::vector<ReportRow>& rows, const std::string& d,
                                                           const MethodId& family, double ReportRow::*field,
                                                           double scale = 1) {
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

static std::vector<Chart> stability_charts(const std::vector<ReportRow>& rows) {
  std::vector<std::string> datasets;
  for (const auto& r : rows)
    if (r.bin == "all" && !r.method.sweep.key.empty() &&
        std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end())
      datasets.push_back(r.dataset);
  std::vector<Chart> charts;
  struct Measure {
    const char* title;
    double scale;
    double ReportRow::*field;
  };
  const Measure measures[] = {{"masked PSNR (dB)", 1, &ReportRow::psnr},
                              {"holes (% of masked pixels)", 100, &ReportRow::hole_rate},
                              {"cracks (% of neighbour pairs)", 100, &ReportRow::crack_rate},
                              {"normal incoherence (deg)", 1, &ReportRow::normal_deg}};
  // One row of charts per dataset and swept key (its own x axis), one chart per measure, one series per
  // method swept over that key.
  for (const auto& d : datasets) {
    const std::vector<MethodId> families = sweep_families(rows, d);
    std::vector<std::string> keys;
    for (const auto& f : families)
      if (std::find(keys.begin(), keys.end(), f.sweep.axis()) == keys.end()) keys.push_back(f.sweep.axis());
    for (const auto& key : keys)
      for (const auto& m : measures) {
        Chart c;
        c.title = d + ": " + key;
        c.x_label = key;
        c.y_label = m.title;
        int k = 0;
        for (const auto& f : families) {
          if (f.sweep.axis() != key) continue;
          const auto pts = sweep_points(rows, d, f, m.field, m.scale);
          ChartSeries s{f.name, {}, {}, true, k % 4, k};
          for (const auto& [x, y] : pts) s.x.push_back(x), s.y.push_back(y);
          c.series.push_back(s);
          ++k;
        }
        charts.push_back(c);
      }
  }
  return charts;
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
    for (const auto& x : results) {
      if (bin >= 0 && x.bin != bin) continue;
      ++r.pairs;
      if (std::isfinite(x.psnr)) p += x.psnr, ++psnr_n;
      s += x.ssim, inf += x.infer_ms, ren += x.render_ms, g += x.gaussians, dec += x.decoded;
      for (const auto& [k, v] : x.stage_ms) stage[k] += v;
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
      DiffRow d{dataset,
                method,
                reference,
                paired_bootstrap(a, b, resamples),
                paired_bootstrap(la, lb, resamples),
                gb > 0 ? ga / gb : nan};
      d.bin = bin < 0 ? "all" : bin_labels[static_cast<size_t>(bin)];
      d.holes = paired_bootstrap(ha, hb, resamples);
      d.cracks = paired_bootstrap(ca, cb, resamples);
      out.push_back(d);
    }
  }
  return out;
}

// How strong a perturbation of `key` is at a swept value (0 = none), and the unit of that strength.
static std::pair<std::function<double(double)>, std::string> perturbation_strength(const std::string& key) {
  if (key.find("noise") != std::string::npos || key == "depth_holes") return {[](double v) { return 100 * v; }, "%"};
  if (key == "depth_scale" || key == "exposure")
    return {[](double v) { return std::abs(std::log(v)); }, "unit of abs(ln value)"};
  if (key == "jpeg_quality") return {[](double v) { return 100 - v; }, "quality point lost"};
  if (key == "prompts") return {[](double v) { return -std::log(v); }, "e-fold fewer"};
  return {[](double v) { return v; }, key == "depth_blur_px" || key == "depth_edge_holes" ? "pixel" : "unit"};
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

// Per dataset: PSNR and hole rate against the baseline group's centre, one series per method that is not
// a sweep point.
static std::vector<Chart> baseline_charts(const std::vector<ReportRow>& breakdowns) {
  std::vector<std::string> datasets;
  for (const auto& r : breakdowns)
    if (std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end()) datasets.push_back(r.dataset);
  std::vector<Chart> charts;
  for (const auto& d : datasets)
    for (int measure = 0; measure < 2; ++measure) {
      Chart c;
      c.title = d + (measure == 0 ? ": masked PSNR against baseline" : ": holes against baseline");
      c.x_label = "baseline (m, group centre)";
      c.y_label = measure == 0 ? "PSNR (dB)" : "holes (% of masked pixels)";
      std::vector<std::string> methods;
      for (const auto& r : breakdowns)
        if (r.dataset == d && !r.method.sweep.any() &&
            std::find(methods.begin(), methods.end(), r.method.name) == methods.end())
          methods.push_back(r.method.name);
      for (size_t k = 0; k < methods.size(); ++k) {
        ChartSeries s{methods[k], {}, {}, true, static_cast<int>(k % 4), static_cast<int>(k)};
        for (const auto& r : breakdowns) {
          if (r.dataset != d || r.method != MethodId{methods[k], {}} || r.bin.rfind("baseline [", 0) != 0) continue;
          const double lo = std::stod(r.bin.substr(10)), hi = std::stod(r.bin.substr(r.bin.find(',') + 1));
          s.x.push_back(0.5 * (lo + hi));
          s.y.push_back(measure == 0 ? r.psnr : 100 * r.hole_rate);
        }
        c.series.push_back(s);
      }
      charts.push_back(c);
    }
  return charts;
}

namespace {
std::vector<std::string> datasets_of(const std::vector<ReportRow>& rows) {
  std::vector<std::string> datasets;
  for (const auto& r : rows)
    if (std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end()) datasets.push_back(r.dataset);
  return datasets;
}

// "0.12 [0.05, 0.20]", with "(no difference)" when the interval contains 0; "n/a" without pairs.
std::string interval_text(const Interval& i, int digits) {
  return i.n == 0 ? std::string("n/a")
                  : cat(format_fixed(i.mean, digits), " [", format_fixed(i.lo, digits), ", ",
                        format_fixed(i.hi, digits), "]", i.excludes_zero() ? "" : " (no difference)");
}

// The columns that name a method in CSV and JSON: its name and its sweep point as typed fields (report.md shows
// the label instead).
void add_method_columns(Table& t) {
  t.columns.insert(t.columns.end(), {{"method"}, {"sweep_key"}, {"budget"}, {"sweep_value", -1}});
}

void add_method_cells(std::vector<TableCell>& cells, const MethodId& m) {
  auto text = [](const std::string& s) { return s.empty() ? TableCell() : TableCell(s); };
  cells.insert(cells.end(), {m.name, text(m.sweep.key), text(m.sweep.budget),
                             m.sweep.any() ? TableCell(m.sweep.value) : TableCell()});
}

// The scores of dataset d: one row per method and bin.
Table scores_table(const std::vector<ReportRow>& rows, const std::string& d, const std::vector<std::string>& nets) {
  Table t;
  t.columns = {{"method"}, {"bin"}, {"pairs"}, {"psnr", 2, "PSNR"}, {"ssim", 4, "SSIM"}};
  for (const auto& n : nets) t.columns.push_back({"lpips_" + n, 4, "LPIPS (" + n + ")"});
  for (const TableColumn& c : std::initializer_list<TableColumn>{
           {"infer_ms", 0, "infer ms"}, {"render_ms", 0, "render ms"}, {"gaussians", 0, "Gaussians"}})
    t.columns.push_back(c);
  for (const auto& r : rows) {
    if (r.dataset != d) continue;
    std::vector<TableCell> cells = {
        r.method.label(), r.bin,
        r.pairs < r.requested ? TableCell(cat(r.pairs, " of ", r.requested)) : TableCell(r.pairs), r.psnr, r.ssim};
    for (const auto& n : nets) cells.push_back(r.lpips.at(n));
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.gaussians});
    t.add(std::move(cells));
  }
  return t;
}

// Where the time goes on dataset d: the stages, the render and the memory, all bins.
Table time_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"Gaussians"}};
  for (const char* st : kStages) t.columns.push_back({st, 1});
  for (const TableColumn& c :
       std::initializer_list<TableColumn>{{"infer", 0}, {"render", 1}, {"peak MB", 0}, {"work MB", 1}})
    t.columns.push_back(c);
  for (const auto& r : rows) {
    if (r.dataset != d || r.bin != "all") continue;
    const bool pruned = std::isfinite(r.decoded) && std::llround(r.decoded) != std::llround(r.gaussians);
    std::vector<TableCell> cells = {r.method.label(),
                                    format_fixed(r.decoded, 0) + (pruned ? " -> " + format_fixed(r.gaussians, 0) : "")};
    for (const char* st : kStages) cells.push_back(r.stage_ms.count(st) ? TableCell(r.stage_ms.at(st)) : TableCell());
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.peak_mb, r.work_mb});
    t.add(std::move(cells));
  }
  return t;
}

// What pruning removed, as mean Gaussians per pair (render/prune_counts), for the methods that prune.
Table pruning_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"decoded"}, {"low opacity"}, {"low contribution"}, {"merged away"}, {"rendered"}};
  for (const auto& r : rows) {
    if (r.dataset != d || r.bin != "all" || r.prune_counts.empty()) continue;
    auto count = [&](const char* k) { return r.prune_counts.count(k) ? r.prune_counts.at(k) : 0.0; };
    t.add({r.method.label(), r.decoded, count("low_opacity"), count("low_contribution"),
           count("merged_members") - count("merged_groups"), r.gaussians});
  }
  return t;
}

// Holes, cracks and normals on dataset d, for the methods that render.
Table stability_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"bin"}, {"holes %", 2}, {"cracks %", 2}, {"normals deg", 2}};
  for (const auto& r : rows)
    if (r.dataset == d && std::isfinite(r.hole_rate))
      t.add({r.method.label(), r.bin, 100 * r.hole_rate, 100 * r.crack_rate, r.normal_deg});
  return t;
}

// The paper's figure for a sweep, where it reports one: Table 4's LiDAR prompt noise (override:prior.sparse.noise,
// family key "noise"), 25.9 -> 23.6 dB on ETH3D from 0% to 5%.
std::string paper_slope(const std::string& key) {
  return key == "noise" ? "-0.46 dB per % (Table 4: ETH3D, 25.9 -> 23.6 dB from 0 to 5%)" : "-";
}

// Per swept family: PSNR against the swept value, its least-squares slope (per 1% for shares and noise
// sigmas) and whether PSNR is monotone in the value (graceful degradation falls steadily with noise). The
// unperturbed run counts as the neutral value (see sweep_points).
Table sweep_table(const std::vector<ReportRow>& rows, const std::string& d, const std::vector<SweepSlope>& intervals) {
  Table t;
  t.columns = {
      {"sweep"},    {"values"}, {"PSNR"}, {"slope"}, {"slope 95% interval (pairs)"}, {"PSNR as strength grows"},
      {"the paper"}};
  std::vector<MethodId> families = sweep_families(rows, d);
  std::sort(families.begin(), families.end(), [](auto& a, auto& b) { return a.family() < b.family(); });
  for (const auto& family : families) {
    auto pts = sweep_points(rows, d, family, &ReportRow::psnr);
    pts.erase(std::remove_if(pts.begin(), pts.end(), [](auto& p) { return !std::isfinite(p.second); }), pts.end());
    if (pts.size() < 2) continue;
    const std::string key = family.sweep.axis();
    const auto [strength, unit] = perturbation_strength(key);
    std::vector<std::pair<double, double>> by_strength;
    for (const auto& [x, y] : pts) by_strength.push_back({strength(x), y});
    std::sort(by_strength.begin(), by_strength.end());
    double mx = 0, my = 0;
    for (const auto& [x, y] : by_strength) mx += x, my += y;
    mx /= static_cast<double>(pts.size()), my /= static_cast<double>(pts.size());
    double sxy = 0, sxx = 0;
    bool falls = true, rises = true;
    for (const auto& [x, y] : by_strength) sxy += (x - mx) * (y - my), sxx += (x - mx) * (x - mx);
    for (size_t k = 1; k < by_strength.size(); ++k)
      falls = falls && by_strength[k].second <= by_strength[k - 1].second,
      rises = rises && by_strength[k].second >= by_strength[k - 1].second;
    const double slope = sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
    std::string xs, ys;
    for (const auto& [x, y] : pts) {
      std::ostringstream v;
      v << std::setprecision(4) << x;
      xs += (xs.empty() ? "" : ", ") + v.str(), ys += (ys.empty() ? "" : ", ") + format_fixed(y, 2);
    }
    const auto ci = std::find_if(intervals.begin(), intervals.end(),
                                 [&](const SweepSlope& s) { return s.dataset == d && s.family == family.family(); });
    const std::string interval =
        ci == intervals.end() || ci->slope.n == 0
            ? std::string("n/a")
            : cat("[", format_fixed(ci->slope.lo, 3), ", ", format_fixed(ci->slope.hi, 3), "] (", ci->slope.n, "): ",
                  ci->slope.hi < 0   ? "falls"
                  : ci->slope.lo > 0 ? "rises"
                                     : "no measurable change");
    t.add({family.family(), xs, ys, format_fixed(slope, 3) + " dB per " + unit, interval,
           falls   ? "falls"
           : rises ? "rises"
                   : "not monotone",
           paper_slope(key)});
  }
  return t;
}

// Finer baseline groups and motion types (see breakdown()): Markdown (`digits` 2/3) or CSV and JSON (4/5).
Table breakdown_table(const std::vector<ReportRow>& breakdowns, const std::string& d,
                      const std::vector<std::string>& nets, bool markdown) {
  Table t;
  const int p = markdown ? 2 : 4, s = markdown ? 3 : 5;
  if (markdown) {
    t.columns.push_back({"method"});
  } else {
    t.columns.push_back({"dataset"});
    add_method_columns(t);
  }
  t.columns.insert(t.columns.end(), {{"group"}, {"pairs"}, {"psnr", p, "PSNR"}, {"ssim", s, "SSIM"}});
  for (size_t k = 0; k < nets.size() && (k == 0 || !markdown); ++k)
    t.columns.push_back({"lpips_" + nets[k], s, "LPIPS"});
  if (markdown) {
    t.columns.insert(t.columns.end(), {{"hole_rate", 2, "holes %"}, {"crack_rate", 2, "cracks %"}});
  } else {
    t.columns.insert(t.columns.end(), {{"hole_rate", 5}, {"crack_rate", 5}, {"normal_deg", 3}});
  }
  const double pct = markdown ? 100 : 1;
  for (const auto& r : breakdowns) {
    if (!d.empty() && r.dataset != d) continue;
    std::vector<TableCell> cells;
    if (markdown) {
      cells.push_back(r.method.label());
    } else {
      cells.push_back(r.dataset);
      add_method_cells(cells, r.method);
    }
    cells.insert(cells.end(), {r.bin, r.pairs, r.psnr, r.ssim});
    for (size_t k = 0; k < nets.size() && (k == 0 || !markdown); ++k) cells.push_back(r.lpips.at(nets[k]));
    cells.insert(cells.end(), {pct * r.hole_rate, pct * r.crack_rate});
    if (!markdown) cells.push_back(r.normal_deg);
    t.add(std::move(cells));
  }
  return t;
}

// One dataset's section of report.md: scores, time, pruning, stability, sweeps and the finer breakdown.
std::string dataset_section(const std::vector<ReportRow>& rows, const std::string& d,
                            const std::vector<std::string>& nets, const std::vector<SweepSlope>& slopes,
                            const std::vector<ReportRow>& breakdowns) {
  std::string md = "## " + d + "\n\n" + table_markdown(scores_table(rows, d, nets));
  md +=
      "\nWhere the time goes (ms per pair, all bins; Gaussians decoded -> rendered after pruning; peak = the process's "
      "resident peak during one prediction and render, which keeps what earlier pairs and methods left resident; work "
      "= the CPU tensor memory one prediction and render needed beyond what was live before, largest over pairs, "
      "which is what a budget changes):\n\n" +
      table_markdown(time_table(rows, d));
  if (const Table pruning = pruning_table(rows, d); !pruning.rows.empty())
    md +=
        "\nPruning (mean Gaussians per pair, all bins): decoded, removed below the opacity floor, removed as faint "
        "over the source and nearby views (largest alpha*T below the threshold), merged away into neighbours, "
        "rendered:\n\n" +
        table_markdown(pruning);
  md +=
      "\nStability: holes = masked pixels with rendered alpha < 0.5; cracks = neighbour pairs whose rendered depth "
      "jumps by > 5% where the reference depth is smooth; normals = mean angle (degrees) between neighbouring "
      "rendered normals on reference-planar surfaces:\n\n" +
      table_markdown(stability_table(rows, d));
  if (const Table sweeps = sweep_table(rows, d, slopes); !sweeps.rows.empty())
    md +=
        "\nSweeps: PSNR (all bins) against the perturbation's strength (noise and shares in %, scale and exposure as "
        "abs(ln value) so both sides count, JPEG as quality lost, prompts as e-folds fewer), its least-squares slope "
        "with its 95% interval over pairs (the mean of per-pair slopes on the pairs every point scored; an interval "
        "containing 0 is no measurable change), and whether the mean PSNR falls steadily as the strength grows "
        "(graceful):\n\n" +
        table_markdown(sweeps);
  if (const Table groups = breakdown_table(breakdowns, d, nets, true); !groups.rows.empty())
    md +=
        "\nBy baseline (finer than the protocol's bins) and by motion type (what moves the image most: lateral or "
        "forward translation, or rotation):\n\n" +
        table_markdown(groups);
  return md + "\n";
}

// Every method against the reference: over all pairs (bin "all") or per bin, for report.md.
Table differences_markdown(const std::vector<DiffRow>& differences, bool per_bin) {
  Table t;
  if (per_bin) {
    t.columns = {{"dataset"}, {"method"}, {"bin"}, {"pairs"}, {"PSNR difference (dB)"}, {"holes"}, {"cracks"}};
  } else {
    t.columns = {{"dataset"},          {"method"}, {"reference"}, {"PSNR difference (dB)"},
                 {"LPIPS difference"}, {"holes"},  {"cracks"},    {"Gaussians, ratio", 2}};
  }
  for (const auto& d : differences) {
    if ((d.bin != "all") != per_bin) continue;
    if (per_bin)
      t.add({d.dataset, d.method.label(), d.bin, d.psnr.n, interval_text(d.psnr, 2), interval_text(d.holes, 2),
             interval_text(d.cracks, 2)});
    else
      t.add({d.dataset, d.method.label(), d.reference, interval_text(d.psnr, 2), interval_text(d.lpips, 3),
             interval_text(d.holes, 2), interval_text(d.cracks, 2), d.gaussians});
  }
  return t;
}

std::string differences_section(const std::vector<DiffRow>& differences) {
  std::string md =
      "## Differences to the reference, on the same pairs\n\nPaired bootstrap 95% intervals (2000 resamples); an "
      "interval that contains 0 is no difference. Holes and cracks in percentage points (n/a where a method does not "
      "render or the data has no depth).\n\n" +
      table_markdown(differences_markdown(differences, false));
  if (const Table per_bin = differences_markdown(differences, true); !per_bin.rows.empty())
    md += "\nPer baseline bin:\n\n" + table_markdown(per_bin);
  return md + "\n";
}

// differences.csv: every difference with its interval's bounds.
Table differences_table(const std::vector<DiffRow>& differences) {
  Table t;
  t.columns = {{"dataset"}};
  add_method_columns(t);
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"bin"}, {"reference"}, {"pairs"}})
    t.columns.push_back(c);
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"psnr_diff", 4},
                                                                 {"psnr_lo", 4},
                                                                 {"psnr_hi", 4},
                                                                 {"lpips_diff", 5},
                                                                 {"lpips_lo", 5},
                                                                 {"lpips_hi", 5},
                                                                 {"holes_pp", 4},
                                                                 {"holes_lo", 4},
                                                                 {"holes_hi", 4},
                                                                 {"cracks_pp", 4},
                                                                 {"cracks_lo", 4},
                                                                 {"cracks_hi", 4}})
    t.columns.push_back(c);
  t.columns.push_back({"gaussians_ratio", 4});
  for (const auto& d : differences) {
    std::vector<TableCell> cells = {d.dataset};
    add_method_cells(cells, d.method);
    cells.insert(cells.end(), {d.bin, d.reference, d.psnr.n});
    for (const Interval* i : {&d.psnr, &d.lpips, &d.holes, &d.cracks})
      cells.insert(cells.end(), {i->mean, i->lo, i->hi});
    cells.push_back(d.gaussians);
    t.add(std::move(cells));
  }
  return t;
}

// slopes.csv: each sweep's PSNR slope with its interval.
Table slopes_table(const std::vector<SweepSlope>& slopes) {
  Table t;
  t.columns = {{"dataset"}, {"sweep"}, {"unit"}, {"pairs"}, {"slope_db", 4}, {"slope_lo", 4}, {"slope_hi", 4}};
  for (const auto& s : slopes) t.add({s.dataset, s.family, s.unit, s.slope.n, s.slope.mean, s.slope.lo, s.slope.hi});
  return t;
}

// report.csv and report.json: every row with every measure.
Table summary_table(const std::vector<ReportRow>& rows, const std::vector<std::string>& nets) {
  Table t;
  t.columns = {{"dataset"}};
  add_method_columns(t);
  for (const TableColumn& c :
       std::initializer_list<TableColumn>{{"bin"}, {"pairs"}, {"requested"}, {"psnr", 4}, {"ssim", 5}})
    t.columns.push_back(c);
  for (const auto& n : nets) t.columns.push_back({"lpips_" + n, 5});
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"infer_ms", 2},
                                                                 {"render_ms", 2},
                                                                 {"gaussians", 0},
                                                                 {"decoded", 0},
                                                                 {"peak_mb", 1},
                                                                 {"work_mb", 2},
                                                                 {"hole_rate", 5},
                                                                 {"crack_rate", 5},
                                                                 {"normal_deg", 3}})
    t.columns.push_back(c);
  for (const char* st : kStages) t.columns.push_back({std::string(st) + "_ms", 2});
  std::set<std::string> pruning;  // what pruning counted, in any row
  for (const auto& r : rows)
    for (const auto& kv : r.prune_counts) pruning.insert(kv.first);
  for (const auto& k : pruning) t.columns.push_back({"prune_" + k, 1});
  for (const auto& r : rows) {
    std::vector<TableCell> cells = {r.dataset};
    add_method_cells(cells, r.method);
    cells.insert(cells.end(), {r.bin, r.pairs, r.requested, r.psnr, r.ssim});
    for (const auto& n : nets) cells.push_back(r.lpips.at(n));
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.gaussians, r.decoded, r.peak_mb, r.work_mb, r.hole_rate,
                               r.crack_rate, r.normal_deg});
    for (const char* st : kStages) cells.push_back(r.stage_ms.count(st) ? TableCell(r.stage_ms.at(st)) : TableCell());
    for (const auto& k : pruning)
      cells.push_back(r.prune_counts.count(k) ? TableCell(r.prune_counts.at(k)) : TableCell());
    t.add(std::move(cells));
  }
  return t;
}
}  // namespace

void write_reports(const std::string& out, const std::vector<ReportRow>& rows, const std::vector<std::string>& nets,
                   const std::vector<std::string>& notes, const std::vector<DiffRow>& differences,
                   const std::vector<ReportRow>& breakdowns, const std::vector<SweepSlope>& slopes) {
  const fs::path dir(out);
  std::string md =
      cat("# Evaluation report\n\nMasked metrics on the protocol's pairs (DESIGN §5). PSNR and SSIM higher is better, "
          "LPIPS lower is better. Times are per pair on this machine. Report written by commit ",
          build_commit(), " (scores resumed from earlier runs keep the commit that computed them).\n\n");
  for (const auto& d : datasets_of(rows)) md += dataset_section(rows, d, nets, slopes, breakdowns);
  if (!differences.empty()) {
    md += differences_section(differences);
    write_table_csv((dir / "differences.csv").string(), differences_table(differences));
  }
  if (!slopes.empty()) write_table_csv((dir / "slopes.csv").string(), slopes_table(slopes));
  if (!notes.empty()) {
    md += "## Notes\n\n";
    for (const auto& n : notes) md += "- " + n + "\n";
  }
  write_file_atomic((dir / "report.md").string(), md);
  const Table summary = summary_table(rows, nets);
  write_table_csv((dir / "report.csv").string(), summary);
  write_table_json((dir / "report.json").string(), summary);
  write_charts((dir / "speed_quality.png").string(), speed_quality_charts(rows), 2, 620, 420);
  const auto stability = stability_charts(rows);
  if (!stability.empty()) write_charts((dir / "stability.png").string(), stability, 4, 360, 260);
  if (!breakdowns.empty()) {
    write_charts((dir / "baseline.png").string(), baseline_charts(breakdowns), 2, 560, 380);
    write_table_csv((dir / "breakdown.csv").string(), breakdown_table(breakdowns, "", nets, false));
  }
}

}  // namespace isplat

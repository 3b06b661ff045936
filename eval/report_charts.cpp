// The report's charts: speed against quality with the Pareto front, stability under sweeps, scores by baseline.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "eval/report.h"
#include "eval/report_parts.h"
#include "io/chart.h"

namespace isplat {

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

namespace reporting {

std::vector<Chart> speed_quality_charts(const std::vector<ReportRow>& rows) {
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

std::vector<Chart> stability_charts(const std::vector<ReportRow>& rows) {
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

// Per dataset: PSNR and hole rate against the baseline group's centre, one series per method that is not
// a sweep point.
std::vector<Chart> baseline_charts(const std::vector<ReportRow>& breakdowns) {
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

}  // namespace reporting
}  // namespace isplat

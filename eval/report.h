// Evaluation reports: per dataset, method and baseline bin (and the average), as Markdown, CSV and JSON,
// plus a speed/quality chart (PNG) drawn with OpenCV.
#pragma once
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "metrics/stats.h"

namespace isplat {

struct PairResult {
  int64_t index = 0;  // position in the manifest
  int bin = 0;
  double baseline = 0;
  double psnr = 0, ssim = 0;
  std::map<std::string, double> lpips;  // NaN = unavailable
  double infer_ms = 0, render_ms = 0;
  int64_t gaussians = 0;  // rendered (after pruning)
  int64_t decoded = 0;    // before pruning (0 in logs that predate it)
  double mask_fraction = 0;
  std::map<std::string, double> stage_ms;  // inference stages: prior, sampler, encoder, decoder, composer, prune
  double peak_mb = std::numeric_limits<double>::quiet_NaN();
};

struct ReportRow {
  std::string dataset, method, bin;  // bin "all" = average over pairs
  int64_t pairs = 0, requested = 0;
  double psnr = 0, ssim = 0;
  std::map<std::string, double> lpips;
  double infer_ms = 0, render_ms = 0, gaussians = 0, decoded = 0;
  std::map<std::string, double> stage_ms;  // means over pairs
  double peak_mb = 0;                      // largest over pairs (NaN when not measured)
};

// Rows for one dataset and method: one per bin label given, then "all".
std::vector<ReportRow> summarize(const std::string& dataset, const std::string& method,
                                 const std::vector<std::string>& bin_labels, const std::vector<int64_t>& requested,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets);

// One method against the reference method on the same pairs: paired bootstrap 95% intervals.
struct DiffRow {
  std::string dataset, method, reference;
  Interval psnr, lpips;  // method − reference (lpips: the first variant scored)
  double gaussians = 0;  // mean Gaussians rendered, method / reference
};

// Differences of every method to `reference` per dataset (empty when the reference was not scored there).
std::vector<DiffRow> paired_differences(const std::string& dataset, const std::string& reference,
                                        const std::map<std::string, std::vector<PairResult>>& results,
                                        const std::string& lpips_net, int64_t resamples = 2000);

// "full@px0.5" -> "full px" (a budget sweep's points form one series); other names pass through.
std::string method_family(const std::string& method);

// Indices of the points (x = cost, y = quality) not dominated by a cheaper-or-equal, better one, by cost.
std::vector<size_t> pareto_front(const std::vector<std::pair<double, double>>& points);

// Writes report.md, report.csv, report.json and speed_quality.png (per dataset: PSNR against time and
// against Gaussians, log scale, one series per method family, the Pareto front marked) into `out`.
void write_reports(const std::string& out, const std::vector<ReportRow>& rows,
                   const std::vector<std::string>& lpips_nets, const std::vector<std::string>& notes,
                   const std::vector<DiffRow>& differences = {});

}  // namespace isplat

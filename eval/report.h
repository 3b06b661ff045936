// Evaluation reports: per dataset, method and baseline bin (and the average), as Markdown, CSV and JSON,
// plus a speed/quality chart (PNG) drawn with OpenCV.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace isplat {

struct PairResult {
  int64_t index = 0;  // position in the manifest
  int bin = 0;
  double baseline = 0;
  double psnr = 0, ssim = 0;
  std::map<std::string, double> lpips;  // NaN = unavailable
  double infer_ms = 0, render_ms = 0;
  int64_t gaussians = 0;
  double mask_fraction = 0;
};

struct ReportRow {
  std::string dataset, method, bin;  // bin "all" = average over pairs
  int64_t pairs = 0, requested = 0;
  double psnr = 0, ssim = 0;
  std::map<std::string, double> lpips;
  double infer_ms = 0, render_ms = 0, gaussians = 0;
};

// Rows for one dataset and method: one per bin label given, then "all".
std::vector<ReportRow> summarize(const std::string& dataset, const std::string& method,
                                 const std::vector<std::string>& bin_labels, const std::vector<int64_t>& requested,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets);

// Writes report.md, report.csv, report.json and speed_quality.png into `out`.
void write_reports(const std::string& out, const std::vector<ReportRow>& rows,
                   const std::vector<std::string>& lpips_nets, const std::vector<std::string>& notes);

}  // namespace isplat

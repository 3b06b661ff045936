// Evaluation reports: per dataset, method and baseline bin (and the average), as Markdown, CSV and JSON,
// plus a speed/quality chart (PNG) drawn with OpenCV.
#pragma once
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "eval/sweep.h"
#include "io/table.h"
#include "metrics/stats.h"

namespace isplat {

// A pair scored again at `factor` times the target's size (scoring.display_factors).
struct DisplayScore {
  double factor = 0;
  double psnr = std::numeric_limits<double>::quiet_NaN();
  double hole_rate = std::numeric_limits<double>::quiet_NaN();
};

// One pair scored on a part of it (scoring.regions): an image region of the target, or the source view re-rendered.
struct RegionScore {
  double share = std::numeric_limits<double>::quiet_NaN();  // of the scored mask's pixels (1 for the source view)
  double psnr = std::numeric_limits<double>::quiet_NaN();
  double lpips = std::numeric_limits<double>::quiet_NaN();    // the first available of scoring.lpips
  double detail = std::numeric_limits<double>::quiet_NaN();   // metrics/regions detail_ratio: below 1 = blurrier
  double density = std::numeric_limits<double>::quiet_NaN();  // Gaussian centres per pixel (centre_density)
};

// A depth-guided method's densified depth (the sparse prior's output) against the true source depth on some pixels:
// AbsRel and the share within 1.25x. NaN where not measured.
struct DensifyScore {
  double abs_rel = std::numeric_limits<double>::quiet_NaN();
  double delta1 = std::numeric_limits<double>::quiet_NaN();
  int64_t pixels = 0;  // scored pixels (pair) or pairs measured (report row)
};

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
  std::map<std::string, double> stage_ms;       // inference stages: prior, sampler, encoder, decoder, composer, prune
  std::map<std::string, int64_t> prune_counts;  // what pruning did (render/prune prune_counts), when enabled
  double peak_mb = std::numeric_limits<double>::quiet_NaN();
  double work_mb = std::numeric_limits<double>::quiet_NaN();  // tensor memory predict + render needed (MethodOutput)
  // Stability (metrics/stability): NaN where the method does not render or the target has no depth.
  double hole_rate = std::numeric_limits<double>::quiet_NaN();
  double crack_rate = std::numeric_limits<double>::quiet_NaN();
  double normal_deg = std::numeric_limits<double>::quiet_NaN();
  double rotation_deg = std::numeric_limits<double>::quiet_NaN();  // between optical axes
  std::string motion;                 // lateral | forward | rotation (eval/pairs motion_type); empty in old logs
  std::vector<DisplayScore> display;  // at scoring.display_factors, for the methods that render Gaussians
  // scoring.regions: by image region (metrics/regions image_regions, plus "all" for the whole mask) and the source
  // view rendered again and scored against the photo (share NaN when not measured).
  std::map<std::string, RegionScore> regions;
  RegionScore source_view;
  // scoring.align_scale: the factor applied to the prediction and the reference samples it was fitted on (NaN and 0
  // when alignment is off or the method renders no Gaussians; 1 and 0 when no sample was usable).
  double scale = std::numeric_limits<double>::quiet_NaN();
  int64_t scale_samples = 0;
  // Sparse-prior methods: the densified depth on valid true-depth pixels that held no prompt, and on those whose
  // depth the perturbation removed (perturb: holes, edge holes, sensor drop-outs), scored against the true depth.
  DensifyScore unprompted, removed;
  MethodId method;  // who scored it (results log fields; a log that predates them is its file's method)
};

struct ReportRow {
  std::string dataset;
  MethodId method;
  std::string bin;  // "all" = average over pairs
  int64_t pairs = 0, requested = 0;
  double psnr = 0, ssim = 0;
  std::map<std::string, double> lpips;
  double infer_ms = 0, render_ms = 0, gaussians = 0, decoded = 0;
  std::map<std::string, double> stage_ms;                // means over pairs
  double peak_mb = 0;                                    // largest over pairs (NaN when not measured)
  double work_mb = 0;                                    // largest over pairs (NaN when not measured)
  double hole_rate = 0, crack_rate = 0, normal_deg = 0;  // means over the pairs where measured (else NaN)
  std::map<std::string, double> prune_counts;            // means over the pairs that pruned (render/prune_counts)
  std::map<double, DisplayScore> display;                // by factor: means over the pairs scored there
  // scoring.align_scale: geometric mean and spread (exp of the std of log factors) over the aligned pairs, how many
  // were aligned and how many had no usable sample (NaN, 0, 0 when off).
  double scale = std::numeric_limits<double>::quiet_NaN(), scale_spread = std::numeric_limits<double>::quiet_NaN();
  int64_t scale_pairs = 0, scale_missed = 0;
  DensifyScore unprompted, removed;  // means over the pairs measured; pixels = those pairs
  // scoring.regions: by region name (PairResult::regions, and "source_view"), each field's mean over the pairs where
  // it is finite.
  std::map<std::string, RegionScore> regions;
};

// Rows for one dataset and method: one per bin label given, then "all".
std::vector<ReportRow> summarize(const std::string& dataset, const MethodId& method,
                                 const std::vector<std::string>& bin_labels, const std::vector<int64_t>& requested,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets);

// The same rows regrouped beyond the protocol's bins: by baseline in steps of `step_m` up to the largest
// scored (bin "baseline [1.5,2)") and by motion type (bin "motion lateral"); groups without pairs are left out.
std::vector<ReportRow> breakdown(const std::string& dataset, const MethodId& method,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets,
                                 double step_m = 0.5);

// One method against the reference method on the same pairs: paired bootstrap 95% intervals.
struct DiffRow {
  std::string dataset;
  MethodId method;
  std::string reference;  // the reference's label (scoring.reference)
  Interval psnr, lpips;   // method − reference (lpips: the first variant scored)
  double gaussians = 0;   // mean Gaussians rendered, method / reference
  std::string bin = "all";
  Interval holes, cracks;  // hole and crack rates, method − reference, in percentage points
};

// Each scored method's results on one dataset, listed by label.
using ScoredMethods = std::map<MethodId, std::vector<PairResult>>;

// Differences of every method to the one labelled `reference` per dataset (empty when the reference was not
// scored there): over all pairs, then per bin for each of `bin_labels` (PairResult::bin indexes them).
std::vector<DiffRow> paired_differences(const std::string& dataset, const std::string& reference,
                                        const ScoredMethods& results, const std::string& lpips_net,
                                        int64_t resamples = 2000, const std::vector<std::string>& bin_labels = {});

// Palette index (tab10) and marker of the k-th method family on the speed/quality charts. The Pareto front is
// grey crosses; no family gets grey, so the front never looks like a method's series.
constexpr int kParetoColor = 7, kParetoMarker = 3;
std::pair<int, int> family_style(size_t k);

// Indices of the points (x = cost, y = quality) not dominated by a cheaper-or-equal, better one, by cost.
std::vector<size_t> pareto_front(const std::vector<std::pair<double, double>>& points);

// A perturbation sweep's PSNR slope on one dataset: the least-squares slope against the perturbation's
// strength (per % for noise and shares), computed per pair over the pairs every point scored and averaged
// (the slope of the mean curve), with a paired bootstrap 95% interval over pairs.
struct SweepSlope {
  std::string dataset, family, unit;  // family: MethodId::family(), e.g. "lidar noise"
  Interval slope;                     // dB per unit; n = pairs
};
std::vector<SweepSlope> sweep_slopes(const std::string& dataset, const ScoredMethods& results,
                                     int64_t resamples = 2000);

// by_region.csv and the report's region section (scoring.regions): per dataset, method, bin and region, the means
// of share, PSNR, LPIPS, detail and density; the section shows bin "all". Empty when no row has regions.
Table regions_table(const std::vector<ReportRow>& rows, bool markdown);

// Writes report.md, report.csv, report.json and speed_quality.png (per dataset: PSNR against time and
// against Gaussians, log scale, one series per method family, the Pareto front marked) into `out`.
void write_reports(const std::string& out, const std::vector<ReportRow>& rows,
                   const std::vector<std::string>& lpips_nets, const std::vector<std::string>& notes,
                   const std::vector<DiffRow>& differences = {}, const std::vector<ReportRow>& breakdowns = {},
                   const std::vector<SweepSlope>& slopes = {});

}  // namespace isplat

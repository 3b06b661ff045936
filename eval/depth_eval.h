// Depth-prior evaluation: AbsRel and delta < 1.25 of one or more priors against the datasets' depth,
// overall and per depth range, on evenly spaced frames of each dataset (the prior issue's report).
#pragma once
#include <string>
#include <vector>

#include "core/runtime.h"
#include "eval/datasets.h"
#include "prior/depth_prior.h"

namespace isplat {

class ConfigVisitor;

struct NamedPrior {
  std::string name = "prior";
  PriorOptions prior;
  void visit(ConfigVisitor& v);
};

struct DepthEvalConfig {
  RuntimeOptions runtime;
  std::vector<EvalDatasetOptions> datasets;
  std::vector<NamedPrior> priors;
  int64_t frames = 24;                                  // frames per dataset, evenly spaced
  std::vector<double> range_edges = {0, 2, 5, 10, 20};  // metres; the last range is open
  std::string out = "out/depth_eval";
  void visit(ConfigVisitor& v);
};

struct DepthScore {
  std::string dataset, prior, range;  // range "all" = every valid pixel
  int64_t frames = 0, pixels = 0;
  double abs_rel = 0, delta1 = 0;  // "all": means over frames; ranges: pooled over their pixels
  // "all" only (NaN for ranges): scale apart from shape. `scale` is the geometric mean over frames of each
  // frame's median pred/ref; `scale_spread` how far a typical frame's scale strays from that mean (the
  // exponential of the standard deviation of the log scales: 1 = the same scale in every frame);
  // `abs_rel_aligned` the mean AbsRel after dividing each frame by its median.
  double scale = 0, scale_spread = 0, abs_rel_aligned = 0;
  double coverage = 0;  // "all" only: share of the reference's valid pixels the prior also marks valid
  double floor = 0;     // "all" only: share of frames scaled from the camera height (NaN when the prior does not)
};

// Scores every prior on every dataset and writes report.md, report.csv and report.json into config.out.
std::vector<DepthScore> evaluate_depth_priors(const DepthEvalConfig& config);

// Per-pixel metrics of one prediction: pred, depth, valid [H,W]; pixels where both are valid count.
struct DepthErrors {
  double abs_rel_sum = 0, delta1_count = 0;
  int64_t pixels = 0;
};
// One frame's scale against the reference (median of pred / ref over the valid pixels) and its AbsRel after
// dividing the prediction by that scale. NaN when no pixel is valid.
struct DepthScale {
  double median_ratio = 0, abs_rel_aligned = 0;
};
DepthScale depth_scale(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& valid);
// The geometric mean of per-frame scales and their spread, exp(std of log scale). NaN when empty.
struct ScaleSummary {
  double mean = 0, spread = 0;
};
ScaleSummary summarize_scales(const std::vector<double>& frame_scales);
DepthErrors depth_errors(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& valid,
                         double lo = 0, double hi = std::numeric_limits<double>::infinity());

}  // namespace isplat

// The evaluator: manifests per dataset, every method scored on the same pairs with the same masks,
// per-pair results appended as they finish (so runs resume), and reports at the end.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "eval/eval_config.h"
#include "eval/methods.h"
#include "eval/report.h"
#include "metrics/metrics.h"

namespace isplat {

class Evaluator {
 public:
  explicit Evaluator(EvalConfig config);
  // Writes manifests; unless pairs_only, scores every method and writes reports. Returns report rows.
  std::vector<ReportRow> run(bool pairs_only = false);

  // The manifest for dataset d: reused when <out>/<name>/manifest.json exists with the same protocol.
  Manifest manifest(size_t d, const std::vector<Sequence>& sequences);
  // Scores one method on a manifest, appending to results_<method>.jsonl and skipping pairs already there.
  // `points` holds each sequence's COLMAP model when the dataset's prompts are points3D, else nothing.
  std::vector<PairResult> score(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                                const MethodOptions& mo, const std::vector<ColmapModel>& points = {});

 private:
  EvalConfig config_;
  std::map<std::string, std::unique_ptr<Lpips>> lpips_;  // available variants
  std::vector<std::string> notes_;
};

}  // namespace isplat

// The evaluator: manifests per dataset, every method scored on the same pairs with the same masks,
// per-pair results appended as they finish (so runs resume), and reports at the end.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "data/colmap.h"
#include "eval/eval_config.h"
#include "eval/methods.h"
#include "eval/report.h"
#include "io/folder_lock.h"
#include "metrics/metrics.h"
#include "metrics/stability.h"

namespace isplat {

// The pair's motion type (eval/pairs motion_type) from the two cameras, the angle between their optical
// axes and the source's median depth (its valid depth, else the prompts' depth; "" when there is none).
std::string pair_motion(const ViewTensors& source, const ViewTensors& target, const torch::Tensor& prompts);

// One scored pair with what produced it (for example panels and the failure gallery).
struct ScoredPair {
  PairResult result;
  ViewTensors source, target;  // unperturbed
  torch::Tensor mask;          // [H,W] the scored region
  MethodOutput output;
};

// The method whose failure-gallery panel `file` is ("<method>_worst_<kind><k>_pair<i>.png"), or "" when the name is
// not a panel's. Exact, so that method "m" never claims the panels of method "m_worst_a".
std::string gallery_panel_method(const std::string& file);

class Evaluator {
 public:
  explicit Evaluator(EvalConfig config);
  // Writes manifests; unless pairs_only, scores every method and writes reports. Returns report rows.
  // A shard (set_shard) scores its share into its own results files and writes no report.
  std::vector<ReportRow> run(bool pairs_only = false);

  // Score only shard `index` of `count`: every count-th pair of each manifest's selection, starting at
  // `index`, into results_<method>.shard-<index>-of-<count>.jsonl. Any machine can run any shard: the
  // manifest (drawn deterministically) is the contract.
  void set_shard(int64_t index, int64_t count);
  // Combines the shard files of `count` shards into the usual results files (checking that every pair is
  // there exactly once), then writes the reports as an unsharded run would.
  std::vector<ReportRow> merge(int64_t count);

  // The manifest for dataset d: reused when <out>/<name>/manifest.json exists with the same protocol.
  // `models`: the COLMAP model per sequence (points3D give depth-free captures their overlap depth), or none.
  Manifest manifest(size_t d, const std::vector<Sequence>& sequences, const std::vector<ColmapModel>& models = {});
  // The manifest positions to score: every pair, or the first scoring.max_per_bin of each bin. This is the
  // one place that cuts the work (a shard of the pairs would be chosen here).
  std::vector<int64_t> select_pairs(const Manifest& m) const;
  // <out>/<dataset>/results_<method>.jsonl, the method name made file-safe.
  std::string dataset_dir(size_t d) const;  // <scoring.out>/<dataset name, sanitized>
  std::string results_path(size_t d, const std::string& method) const;
  // Scores one method on the given pairs of a manifest, appending to results_<method>.jsonl and skipping
  // pairs already there. `points` holds each sequence's COLMAP model when the dataset's prompts are
  // points3D, else nothing. Returns the results of exactly `pairs`, in manifest order; empty (with a note)
  // when the method needs the source depth and the dataset has none.
  std::vector<PairResult> score(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                                const std::vector<int64_t>& pairs, const MethodOptions& mo,
                                const std::vector<ColmapModel>& points = {});

 private:
  // Loads, (perturbs,) predicts and scores manifest pair i.
  // One pair's target rendered again at `factor` times its size, scored against the target and mask resized to match.
  DisplayScore score_display(const MethodOutput& output, const ViewTensors& target, const torch::Tensor& mask,
                             double factor) const;
  ScoredPair score_pair(size_t d, const std::vector<Sequence>& sequences, const Manifest& m, int64_t i,
                        const MethodOptions& mo, Method& method, const std::vector<ColmapModel>& points,
                        bool has_depth);
  // The crack measure's options from scoring (crack_edge_margin, crack_holes, crack_side, crack_min_error,
  // crack_edge_side).
  StabilityOptions crack_options() const;
  // The maps the scores read: the median depth too when scoring.crack_depth = median.
  RenderMaps scoring_maps() const;
  // The failure gallery (scoring.gallery): the worst pairs by PSNR, by hole rate and by crack rate, re-rendered into
  // <dataset>/gallery/ as source, target, prediction, error, rendered normals, alpha and (where the target has
  // depth) the crack map. Existing panels are kept.
  void write_gallery(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                     const std::vector<PairResult>& results, const MethodOptions& mo,
                     const std::vector<ColmapModel>& points, bool has_depth);

  // Locks scoring.out (io/folder_lock.h) for this evaluator's life: a second evaluation into the same folder fails
  // at once naming it and the holder's pid. Each shard of a sharded run has its own lock.
  void lock_output();

  // The COLMAP points3D of dataset d that scoring.align_scale = points fits on, loaded once (Error for other formats).
  const std::vector<ColmapModel>& alignment_points(size_t d);

  EvalConfig config_;
  std::map<size_t, std::vector<ColmapModel>> align_models_;
  std::unique_ptr<FolderLock> lock_;
  std::map<std::string, std::unique_ptr<Lpips>> lpips_;  // available variants
  std::vector<std::string> notes_;
  int64_t shard_index_ = 0, shard_count_ = 1;
};

}  // namespace isplat

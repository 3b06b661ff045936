// Depth-prior evaluation: AbsRel / delta1 on hand-built maps, and a report over a tiny dataset where the
// oracle prior scores perfectly and an untrained net does not.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <filesystem>

#include "eval/depth_eval.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("depth eval: AbsRel and delta1 on hand-built maps", "[eval][depth]") {
  const auto depth = torch::tensor({{1.0f, 2.0f}, {4.0f, 8.0f}});
  const auto pred = torch::tensor({{1.1f, 2.0f}, {2.0f, 8.0f}});   // +10 %, exact, half, exact
  const auto valid = torch::tensor({{1.0f, 1.0f}, {1.0f, 0.0f}});  // the last pixel does not count
  const DepthErrors e = depth_errors(pred, depth, valid);
  CHECK(e.pixels == 3);
  CHECK(e.abs_rel_sum == Approx(0.1 + 0.0 + 0.5));
  CHECK(e.delta1_count == Approx(2.0));                                 // 1.1 and 1.0 pass; 2.0 does not
  const DepthErrors near = depth_errors(pred, depth, valid, 0.0, 3.0);  // only depths in [0, 3) m
  CHECK(near.pixels == 2);
  CHECK(near.abs_rel_sum == Approx(0.1));
  // Scale apart from shape: twice the reference is scale 2 with no shape error; a bent map keeps some.
  const auto ref = torch::tensor({{1.0f, 2.0f}, {4.0f, 8.0f}});
  const DepthScale twice = depth_scale(2 * ref, ref, torch::ones({2, 2}));
  CHECK(twice.median_ratio == Approx(2.0));
  CHECK(twice.abs_rel_aligned == Approx(0.0).margin(1e-12));
  const DepthScale bent = depth_scale(ref * torch::tensor({{2.0f, 2.0f}, {2.0f, 3.0f}}), ref, torch::ones({2, 2}));
  CHECK(bent.median_ratio == Approx(2.0));  // lower median of {2, 2, 2, 3}
  CHECK(bent.abs_rel_aligned == Approx(0.5 / 4));
  CHECK(std::isnan(depth_scale(ref, ref, torch::zeros({2, 2})).median_ratio));
  // Per-frame scales: a steady bias has no spread; half in one frame and twice in the next average to 1
  // with a spread of 2.
  const ScaleSummary steady = summarize_scales({2.0, 2.0, 2.0});
  CHECK(steady.mean == Approx(2.0));
  CHECK(steady.spread == Approx(1.0));
  const ScaleSummary noisy = summarize_scales({0.5, 2.0});
  CHECK(noisy.mean == Approx(1.0));
  CHECK(noisy.spread == Approx(2.0));
  CHECK(std::isnan(summarize_scales({}).mean));
}

TEST_CASE("depth eval: the oracle scores perfectly, an untrained net does not, per range", "[eval][depth]") {
  test::QuietLogs quiet;
  auto g = test::eval_dataset_options(test::temp_dir("depth_eval_data"), 8, {"courtyard_colmap"});
  generate_datasets(g);
  DepthEvalConfig c;
  EvalDatasetOptions ds;
  ds.name = "courtyard";
  ds.format = "colmap";
  ds.root = generated_eval_root(g.out, "courtyard_colmap");
  c.datasets = {ds};
  NamedPrior oracle, untrained;
  oracle.name = "oracle";
  oracle.prior.type = "dataset";
  untrained.name = "untrained";
  untrained.prior.type = "learned";
  untrained.prior.learned_width = 8;
  c.priors = {oracle, untrained};
  c.frames = 3;
  c.out = test::temp_dir("depth_eval_out");
  const auto scores = evaluate_depth_priors(c);
  REQUIRE(scores.size() == 2 * (1 + c.range_edges.size()));
  for (const auto& s : scores) {
    if (s.range != "all") continue;
    CHECK(s.frames == 3);
    if (s.prior == "oracle") {
      CHECK(s.abs_rel == Approx(0.0).margin(1e-6));
      CHECK(s.delta1 == Approx(1.0));
      CHECK(s.scale == Approx(1.0));
      CHECK(s.scale_spread == Approx(1.0));
      CHECK(s.abs_rel_aligned == Approx(0.0).margin(1e-6));
      CHECK(s.coverage == Approx(1.0));
    } else {
      CHECK(s.abs_rel > 0.05);
    }
  }
  int64_t range_pixels = 0, all_pixels = 0;
  for (const auto& s : scores)
    if (s.prior == "oracle") (s.range == "all" ? all_pixels : range_pixels) += s.pixels;
  CHECK(range_pixels == all_pixels);  // the ranges partition the valid pixels
  for (const char* f : {"report.md", "report.csv", "report.json"}) CHECK(fs::exists(fs::path(c.out) / f));
  CHECK_THAT(test::read_bytes(c.out + "/report.md"),
             Catch::Contains("| oracle | 0.000 | 1.000 | 1.000 | 1.000 | 0.000 | 1.000 |"));
}

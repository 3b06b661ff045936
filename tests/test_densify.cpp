// Densification measured directly: the scores on pixels without prompts and on pixels a perturbation removed, and a
// depth-guided method scored with the sensor preset reports them beside PSNR.
#include <catch2/catch.hpp>

#include "core/config.h"
#include "eval/densify.h"
#include "eval/evaluator.h"
#include "io/jsonl.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

namespace densify_test {
using namespace isplat;

TEST_CASE("densify: AbsRel and delta1 on unprompted and on removed pixels", "[eval][densify]") {
  const int64_t W = 10, H = 4;
  const auto truth = torch::full({H, W}, 2.0f);
  auto valid = torch::ones({H, W});
  valid[0][0] = 0;  // no true depth: never scored
  auto seen = valid.clone();
  seen.narrow(1, 8, 2).fill_(0);           // the perturbation removed the last two columns (8 pixels)
  auto dense = torch::full({H, W}, 2.2f);  // 10% off everywhere ...
  dense.narrow(1, 8, 2).fill_(3.0f);       // ... 50% off where the sensor had nothing
  dense[3][7] = 0;                         // a pixel the densifier left out: not scored
  const auto prompts = torch::tensor({{1, 1}, {2, 1}, {9, 3}, {40, 2}}, torch::kLong);  // (col, row); one outside
  const DensifyScores s = score_densification(dense, prompts, truth, valid, seen);
  // Unprompted: 40 - 1 (no truth) - 3 (prompts) - 1 (left out) = 35 pixels; 28 at 10% and 7 removed ones at 50% (the
  // eighth, (9, 3), held a prompt).
  CHECK(s.unprompted.pixels == 35);
  CHECK(s.unprompted.abs_rel == Approx((28 * 0.1 + 7 * 0.5) / 35));
  CHECK(s.unprompted.delta1 == Approx(28.0 / 35));
  CHECK(s.removed.pixels == 8);
  CHECK(s.removed.abs_rel == Approx(0.5));
  CHECK(s.removed.delta1 == 0.0);
  // Nothing removed: no removed score.
  const DensifyScores none = score_densification(dense, prompts, truth, valid, valid);
  CHECK(none.removed.pixels == 0);
  CHECK(std::isnan(none.removed.abs_rel));
}

TEST_CASE("densify: a depth-guided method under the sensor preset reports its densification beside PSNR",
          "[eval][densify]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("densify_data", 16);
  const std::string ck = test::temp_dir("densify_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("densify_run"), 1)).save(ck);
  EvalConfig c;
  EvalDatasetOptions ds;
  ds.name = "courtyard";
  ds.root = generated_eval_root(g.out, "courtyard_colmap");
  c.datasets = {ds};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("densify_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  MethodOptions sensor =
      named_method("lidar_kinect", "model", ck,
                   {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none", "prior.sparse.prompts=200"});
  sensor.perturb.sensor.preset = "kinect";
  c.methods = {
      named_method("lift", "lift"),
      named_method("lidar", "model", ck,
                   {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none", "prior.sparse.prompts=200"}),
      sensor};
  const auto rows = Evaluator(c).run();
  auto all = [&](const std::string& m) {
    for (const auto& r : rows)
      if (r.method.label() == m && r.bin == "all") return r;
    FAIL("no row for " << m);
    return ReportRow{};
  };
  const ReportRow lidar = all("lidar"), kinect = all("lidar_kinect"), lift = all("lift");
  CHECK(lidar.unprompted.pixels == lidar.pairs);  // every pair measured
  CHECK(lidar.unprompted.abs_rel > 0);
  CHECK(lidar.unprompted.delta1 > 0.5);
  CHECK(lidar.removed.pixels == 0);  // nothing removed without a perturbation
  CHECK(kinect.removed.pixels == kinect.pairs);
  CHECK(std::isfinite(kinect.removed.abs_rel));
  CHECK(lift.unprompted.pixels == 0);  // not a sparse prior
  for (const auto& j : read_jsonl(c.scoring.out + "/courtyard/results_lidar_kinect.jsonl")) {
    CHECK(j.at("densify_removed").at("pixels").get<int64_t>() > 0);
    CHECK(j.at("densify_unprompted").at("delta1").get<double>() <= 1.0);
  }
  const std::string md = test::read_bytes(c.scoring.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("Densification (sparse-prior methods)") && Catch::Contains("| lidar_kinect | all |"));
  CHECK_THAT(test::read_bytes(c.scoring.out + "/report.csv"), Catch::Contains("densify_removed_abs_rel"));
}

TEST_CASE("densify: scoring.mask_depth = seen leaves a sensor's holes unscored", "[eval][densify]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("mask_seen_data", 16);
  EvalConfig c;
  EvalDatasetOptions ds;
  ds.name = "courtyard";
  ds.root = generated_eval_root(g.out, "courtyard_colmap");
  c.datasets = {ds};
  c.protocol.pairs_per_bin = 2;
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  MethodOptions clean = named_method("lift", "lift"), holes = named_method("lift_holes", "lift");
  holes.perturb.depth_holes = 0.4;  // 40% of the source depth gone, in blobs
  c.methods = {clean, holes};
  auto masks = [&](const std::string& mask_depth) {
    c.scoring.mask_depth = mask_depth;
    c.scoring.out = test::temp_dir("mask_seen_out_" + mask_depth);
    Evaluator(c).run();
    std::map<std::string, std::vector<double>> fraction;
    for (const std::string m : {"lift", "lift_holes"})
      for (const auto& j : read_jsonl(c.scoring.out + "/courtyard/results_" + m + ".jsonl"))
        fraction[m].push_back(j.at("mask_fraction").get<double>());
    return fraction;
  };
  auto truth = masks("true"), seen = masks("seen");
  REQUIRE(!truth["lift"].empty());
  CHECK(truth["lift"] == truth["lift_holes"]);  // the default: the same pixels for every method
  CHECK(seen["lift"] == truth["lift"]);         // no perturbation: nothing changes
  for (size_t i = 0; i < seen["lift_holes"].size(); ++i)
    CHECK(seen["lift_holes"][i] < truth["lift_holes"][i]);  // the holes are not scored
  CHECK_THROWS_WITH(config_from_json<EvalConfig>(nlohmann::json{{"scoring", {{"mask_depth", "sensor"}}}}, "t.json"),
                    Catch::Contains("mask_depth"));
}

}  // namespace densify_test

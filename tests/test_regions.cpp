// Scores by image region: the region masks, the detail ratio and the Gaussian density on images whose answers are
// known, and the evaluator's scoring.regions end to end (records, report, stamp, damaged records).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include <torch/torch.h>

#include "core/config.h"
#include "eval/evaluator.h"
#include "eval/results_log.h"
#include "metrics/regions.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;

namespace regions_test {

// A 3x24x32 image: a black-and-white checkerboard of 2 px squares on the left half, flat grey on the right.
torch::Tensor half_textured() {
  auto image = torch::full({3, 24, 32}, 0.5f);
  for (int64_t y = 0; y < 24; ++y)
    for (int64_t x = 0; x < 16; ++x) image.select(1, y).select(1, x).fill_(((x / 2 + y / 2) % 2) ? 1.0f : 0.0f);
  return image;
}

torch::Tensor region(const std::vector<std::pair<std::string, torch::Tensor>>& regions, const std::string& name) {
  for (const auto& [n, m] : regions)
    if (n == name) return m;
  FAIL("no region " << name);
  return {};
}

}  // namespace regions_test

TEST_CASE("regions: near and far, silhouettes and interiors, textured and flat split the scored mask",
          "[metrics][regions]") {
  using namespace regions_test;
  const auto image = half_textured();
  // Depth 1 m on the top 12 rows, 3 m below; the bottom-right 4x4 corner has none.
  auto depth = torch::full({24, 32}, 1.0f);
  depth.slice(0, 12, 24).fill_(3.0f);
  depth.slice(0, 20, 24).slice(1, 28, 32).fill_(0.0f);
  auto mask = torch::ones({24, 32});
  mask.slice(1, 0, 2).fill_(0);  // two columns not scored
  const auto regions = image_regions(image, depth, mask);
  REQUIRE(regions.size() == 6);
  const auto near = region(regions, "near"), far = region(regions, "far");
  const auto silhouette = region(regions, "silhouette"), interior = region(regions, "interior");
  const auto textured = region(regions, "textured"), flat = region(regions, "flat");
  // Near and far are the two halves of the valid, scored depth; nothing outside the mask is in any region.
  CHECK(near.slice(0, 0, 12).slice(1, 2, 32).min().item<float>() == 1);
  CHECK(near.slice(0, 12, 24).sum().item<float>() == 0);
  CHECK(far.slice(0, 12, 20).slice(1, 2, 32).min().item<float>() == 1);
  CHECK(far.slice(0, 20, 24).slice(1, 28, 32).sum().item<float>() == 0);  // no depth: neither
  for (const auto& [name, m] : regions) CHECK(m.slice(1, 0, 2).sum().item<float>() == 0);
  // The silhouette band is the rows within 2 px of the depth step (rows 10..13 hold the edge's pixels 11 and 12),
  // and around the corner without depth; the interior is the rest of the valid depth.
  CHECK(silhouette.slice(0, 9, 15).slice(1, 2, 24).min().item<float>() == 1);
  CHECK(silhouette.slice(0, 0, 9).slice(1, 2, 24).sum().item<float>() == 0);
  CHECK(silhouette[17][26].item<float>() == 1);  // 2 px from the corner's edge pixel (19, 28) beside the missing depth
  CHECK(interior.slice(0, 0, 9).slice(1, 2, 32).min().item<float>() == 1);
  CHECK(((silhouette + interior) * (depth > 0)).max().item<float>() == 1);
  CHECK((silhouette * interior).sum().item<float>() == 0);
  // The checkerboard is textured, the grey half flat, and the two split the scored mask exactly.
  CHECK(textured.slice(1, 3, 14).min().item<float>() == 1);
  CHECK(textured.slice(1, 19, 32).sum().item<float>() == 0);
  CHECK(torch::equal(textured + flat, mask));
  // Without reference depth only the texture split is made.
  CHECK(image_regions(image, torch::Tensor(), mask).size() == 2);
  CHECK_THROWS_WITH(image_regions(image, depth.slice(0, 0, 10), mask), Catch::Contains("reference depth"));
}

TEST_CASE("regions: the detail ratio is 1 for the target itself, below 1 when blurred, above when noisy",
          "[metrics][regions]") {
  using namespace regions_test;
  torch::manual_seed(3);
  const auto image = half_textured();
  const auto mask = torch::ones({24, 32});
  CHECK(detail_ratio(image, image, mask) == Approx(1.0));
  const auto blurred = torch::avg_pool2d(image.unsqueeze(0), 3, 1, 1, false, false).squeeze(0);
  CHECK(detail_ratio(blurred, image, mask) < 0.5);
  const auto mid = 0.25 + 0.5 * image;  // room for noise both ways
  const auto noisy = (mid + 0.1 * torch::randn_like(image)).clamp(0, 1);
  CHECK(detail_ratio(noisy, mid, mask) > 1.0);
  // Only the masked pixels count: on the flat half alone the target has no detail, so there is no ratio.
  auto right = torch::zeros({24, 32});
  right.slice(1, 20, 32).fill_(1);
  CHECK(std::isnan(detail_ratio(noisy, mid, right)));
  CHECK(std::isnan(detail_ratio(image, image, torch::zeros({24, 32}))));
}

TEST_CASE("regions: Gaussian density counts the centres in front of the camera that land on the mask",
          "[metrics][regions]") {
  Camera camera;
  camera.K = make_K(10, 10, 4, 4);
  camera.T_cw = torch::eye(4);
  camera.width = camera.height = 8;
  // Two centres on pixel (1, 1), one on (6, 6), one behind the camera (would land on (1, 1)), one outside the image.
  const auto means = torch::tensor({-0.25f, -0.25f, 1.0f, -0.25f, -0.25f, 1.0f, 0.25f, 0.25f, 1.0f, 0.25f, 0.25f, -1.0f,
                                    5.0f, 0.0f, 1.0f})
                         .view({5, 3});
  auto top_left = torch::zeros({8, 8});
  top_left.slice(0, 0, 4).slice(1, 0, 4).fill_(1);
  CHECK(centre_density(means, camera, top_left) == Approx(2.0 / 16));
  CHECK(centre_density(means, camera, torch::ones({8, 8})) == Approx(3.0 / 64));
  CHECK(std::isnan(centre_density(means, camera, torch::zeros({8, 8}))));
  CHECK_THROWS_WITH(centre_density(means, camera, torch::ones({4, 8})), Catch::Contains("mask must be [8,8]"));
}

TEST_CASE("eval: scoring.regions records each pair by region and in its source view, and reports them",
          "[eval][regions]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_regions", 16);
  EvalConfig c;
  c.datasets = {test::tiny_courtyard_set(g)};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("eval_regions_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  c.scoring.regions = true;
  const auto rows = Evaluator(c).run();
  const std::string log = test::read_bytes(c.scoring.out + "/courtyard/results_lift.jsonl");
  const auto first = nlohmann::json::parse(log.substr(0, log.find('\n')));
  const PairResult r = result_from_json(first);
  // The whole mask, then the six regions of a target with depth; each half pair splits the mask.
  REQUIRE(r.regions.size() == 7);
  CHECK(r.regions.at("all").psnr == Approx(r.psnr));
  CHECK(r.regions.at("near").share + r.regions.at("far").share == Approx(1.0).margin(0.05));
  CHECK(r.regions.at("textured").share + r.regions.at("flat").share == Approx(1.0));
  CHECK(std::isnan(r.regions.at("all").lpips));  // no LPIPS variant asked for
  // lift puts one Gaussian on each valid source pixel: about one per pixel in the source view, which it reproduces
  // nearly exactly (a pure representation test).
  CHECK(r.source_view.density == Approx(1.0).margin(0.1));
  CHECK(r.source_view.psnr > r.psnr);
  CHECK(r.regions.at("all").detail > 0);
  // identity renders no scene: regions, but no source view and no density.
  const std::string id_log = test::read_bytes(c.scoring.out + "/courtyard/results_identity.jsonl");
  const PairResult id = result_from_json(nlohmann::json::parse(id_log.substr(0, id_log.find('\n'))));
  CHECK(id.regions.size() == 7);
  CHECK(std::isnan(id.source_view.share));
  CHECK(std::isnan(id.regions.at("all").density));
  // The report's section and table; the stamp holds the option, so scores without regions never resume these.
  CHECK_THAT(test::read_bytes(c.scoring.out + "/report.md"),
             Catch::Contains("## By image region") && Catch::Contains("source_view"));
  CHECK_THAT(test::read_bytes(c.scoring.out + "/by_region.csv"), Catch::Contains("courtyard,lift,,,,all,silhouette,"));
  bool summarized = false;
  for (const auto& row : rows)
    summarized = summarized || (row.method.label() == "lift" && row.bin == "all" && row.regions.count("source_view"));
  CHECK(summarized);
  EvalConfig other = c;
  other.scoring.regions = false;
  CHECK_THROWS_WITH(Evaluator(other).run(), Catch::Contains("was scored with other options"));
  // A damaged region score is named.
  auto bad = first;
  bad["regions"]["near"]["detail"] = -1;
  CHECK_THROWS_WITH(result_from_json(bad), Catch::Contains("regions.near.detail"));
  bad = first;
  bad["source_view"].erase("psnr");
  CHECK_THROWS(result_from_json(bad));
}

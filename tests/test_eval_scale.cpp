// Scale alignment (scoring.align_scale): the same manifest of a capture whose poses, points and depth are scaled by
// 3.7 scores as the original to float precision with alignment on, the fit and the scaling about the camera, and
// alignment off leaves the results as they were.
#include <catch2/catch.hpp>

#include <filesystem>

#include <opencv2/core.hpp>

#include "core/log.h"
#include "data/colmap.h"
#include "eval/evaluator.h"
#include "eval/results_log.h"
#include "io/depth_io.h"
#include "io/jsonl.h"
#include "render/scale_align.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

namespace scale_test {
using namespace isplat;
namespace fs = std::filesystem;

// A copy of the COLMAP capture under `root` with every camera centre, 3D point and depth value multiplied by `s`.
std::string scaled_copy(const std::string& root, double s, const std::string& tag) {
  const std::string out = test::temp_dir(tag);
  fs::copy(root, out, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  for (const auto& scene : fs::directory_iterator(out)) {
    const std::string sparse = (scene.path() / "sparse" / "0").string();
    ColmapModel m = read_colmap(sparse);
    for (auto& [id, img] : m.images) img.tvec *= s;  // C = -R^T t: scaling t scales the centre
    for (auto& [id, p] : m.points) p.xyz *= s;
    for (const auto& f : fs::directory_iterator(sparse)) fs::remove(f.path());
    write_colmap_text(sparse, m);
    write_colmap_binary(sparse, m);
    for (const auto& f : fs::directory_iterator(scene.path() / "depth")) {
      const DepthMap d = read_depth_exr(f.path().string());
      write_depth_exr(f.path().string(), d.depth * s);
    }
  }
  return out;
}

EvalDatasetOptions courtyard(const std::string& root) {
  EvalDatasetOptions d;
  d.name = "courtyard";
  d.format = "colmap";
  d.root = root;
  return d;
}

// The results of method `mo` on the pairs of manifest `m`, scored on dataset `ds` into `out`.
std::vector<PairResult> score_on(const EvalDatasetOptions& ds, const std::string& align, const std::string& out,
                                 const Manifest& m, const MethodOptions& mo) {
  EvalConfig c;
  c.datasets = {ds};
  c.scoring.out = out;
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  c.scoring.align_scale = align;
  Evaluator ev(c);
  torch::manual_seed(11);  // the untrained learned net is initialized from the global generator: the same net each time
  return ev.score(0, load_eval_dataset(ds), m, ev.select_pairs(m), mo);
}

TEST_CASE("scale alignment: a capture scaled by 3.7 scores as the original, pair by pair", "[eval][scale]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("scale_data", 16);
  const std::string ck = test::temp_dir("scale_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("scale_run"), 1)).save(ck);
  const EvalDatasetOptions original = courtyard(generated_eval_root(g.out, "courtyard_colmap"));
  const EvalDatasetOptions scaled = courtyard(scaled_copy(original.root, 3.7, "scale_copy"));
  // The manifest is the original's: the same pairs on both captures.
  EvalConfig c;
  c.datasets = {original};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("scale_manifest");
  const Manifest m = Evaluator(c).manifest(0, load_eval_dataset(original));
  REQUIRE(m.pairs.size() >= 4);
  // A model whose depth comes from the image alone (an untrained learned net): its scale knows nothing of the capture.
  // (lift and a dataset prior read the dataset's depth, so their predictions are in its units already; the sampler's
  // release edge threshold grows with log depth, so they are not expected to score identically at another scale.)
  const MethodOptions model = named_method("mono", "model", ck, {"prior.type=learned"});
  for (const std::string align : {"points", "depth"}) {
    INFO(align);
    const auto a = score_on(original, align, test::temp_dir("scale_a"), m, model);
    const auto b = score_on(scaled, align, test::temp_dir("scale_b"), m, model);
    REQUIRE(a.size() == m.pairs.size());
    REQUIRE(b.size() == a.size());
    for (size_t k = 0; k < a.size(); ++k) {
      INFO("pair " << a[k].index);
      REQUIRE(a[k].scale_samples > 0);
      CHECK(b[k].scale_samples == a[k].scale_samples);
      CHECK(b[k].scale == Approx(3.7 * a[k].scale).epsilon(1e-5));
      CHECK(b[k].psnr == Approx(a[k].psnr).margin(1e-3));
      CHECK(b[k].hole_rate == Approx(a[k].hole_rate).margin(1e-3));
    }
  }
  // Without alignment the image-only model lands 3.7 times too near on the scaled capture: the scores differ.
  const auto a = score_on(original, "none", test::temp_dir("scale_off_a"), m, model);
  const auto b = score_on(scaled, "none", test::temp_dir("scale_off_b"), m, model);
  double largest = 0;
  for (size_t k = 0; k < a.size(); ++k) largest = std::max(largest, std::abs(a[k].psnr - b[k].psnr));
  CHECK(largest > 0.1);
}

TEST_CASE("scale alignment: off by default, recorded when on, and refused where it has no reference", "[eval][scale]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("scale_off", 16);
  EvalConfig c;
  c.datasets = {courtyard(generated_eval_root(g.out, "courtyard_colmap"))};
  c.protocol.pairs_per_bin = 2;
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  CHECK(c.scoring.align_scale == "none");
  c.scoring.out = test::temp_dir("scale_off_out");
  const auto rows = Evaluator(c).run();
  // Off: the records carry no alignment fields, and lift's PSNR is that of a render of its own unscaled scene, the
  // path every method took before the option existed (an empty AlignScene is never called).
  for (const auto& j : read_jsonl(c.scoring.out + "/courtyard/results_lift.jsonl")) CHECK_FALSE(j.contains("scale"));
  for (const auto& r : rows) CHECK(r.scale_pairs == 0);
  CHECK_THAT(test::read_bytes(c.scoring.out + "/report.md"), !Catch::Contains("Scale alignment"));
  // A stamp of a run before the option adopts its default, none, and only that.
  const std::string stamp = c.scoring.out + "/courtyard/results_lift.jsonl.method.json";
  auto js = nlohmann::json::parse(test::read_bytes(stamp));
  REQUIRE(js.value("scoring.align_scale", "") == "none");
  js.erase("scoring.align_scale");
  test::write_bytes(stamp, js.dump());
  const auto again = Evaluator(c).run();
  CHECK(again[4].psnr == rows[4].psnr);
  EvalConfig on = c;
  on.scoring.align_scale = "points";
  CHECK_THROWS_WITH(Evaluator(on).run(), Catch::Contains("was scored with other options"));
  // On: every rendering method's records carry the factor; the report has the table; identity has nothing to scale.
  on.scoring.out = test::temp_dir("scale_on_out");
  Evaluator(on).run();
  for (const auto& j : read_jsonl(on.scoring.out + "/courtyard/results_lift.jsonl")) {
    CHECK(j.at("scale").get<double>() == Approx(1.0).epsilon(0.1));  // lift stands on the dataset's own depth
    CHECK(j.at("scale_samples").get<int64_t>() > 0);
  }
  for (const auto& j : read_jsonl(on.scoring.out + "/courtyard/results_identity.jsonl"))
    CHECK_FALSE(j.contains("scale"));
  const std::string md = test::read_bytes(on.scoring.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("Scale alignment") && Catch::Contains("scoring.align_scale = points"));
  CHECK_THAT(test::read_bytes(on.scoring.out + "/report.csv"), Catch::Contains("scale_spread"));
  // Points need a COLMAP dataset; depth needs depth.
  EvalConfig ns = on;
  ns.datasets[0].format = "nerfstudio";
  ns.datasets[0].root = generated_eval_root(g.out, "atrium_nerfstudio");
  ns.scoring.out = test::temp_dir("scale_ns_out");
  CHECK_THROWS_WITH(Evaluator(ns).run(), Catch::Contains("align_scale = points needs COLMAP points3D"));
  EvalConfig nodepth = on;
  nodepth.datasets[0].depth_format = "none";
  nodepth.scoring.align_scale = "depth";
  nodepth.scoring.out = test::temp_dir("scale_nodepth_out");
  CHECK_THROWS_WITH(Evaluator(nodepth).run(),
                    Catch::Contains("align_scale = depth, but dataset 'courtyard' has no depth"));
}

TEST_CASE("scale alignment: the fit is the median ratio, the scaling keeps the view from the camera", "[eval][scale]") {
  // A fronto-parallel plane of Gaussians at z = 2 in front of a camera that is not at the origin.
  const int64_t W = 16, H = 12, N = W * H;
  auto K = torch::tensor({20.0, 0.0, 8.0, 0.0, 20.0, 6.0, 0.0, 0.0, 1.0}).reshape({3, 3});
  auto T = torch::eye(4);
  T[0][3] = 0.5, T[1][3] = -0.25, T[2][3] = 1.0;  // world -> camera: the centre is at (-0.5, 0.25, -1)
  const Camera cam{K, T, W, H};
  auto j = torch::arange(W).repeat({H}).to(torch::kFloat32),
       i = torch::arange(H).repeat_interleave(W).to(torch::kFloat32);
  const auto cam_pts = torch::stack({(j + 0.5 - 8) * 2 / 20, (i + 0.5 - 6) * 2 / 20, torch::full({N}, 2.0)}, 1);
  const auto world = cam_pts - T.slice(0, 0, 3).select(1, 3);
  const Gaussians g{world, torch::full({N, 3}, 0.08), torch::tensor({1.0, 0.0, 0.0, 0.0}).repeat({N, 1}),
                    torch::full({N, 3}, 0.5), torch::full({N}, 0.9)};
  // Reference depth 3.0 at most samples, outliers elsewhere: the median ignores them.
  auto samples =
      torch::tensor({{2.5, 3.5, 3.0}, {8.5, 6.5, 3.0}, {10.5, 2.5, 3.0}, {4.5, 8.5, 30.0}, {12.5, 9.5, 0.1}});
  const ScaleFit fit = fit_scene_scale(g, cam, samples);
  CHECK(fit.samples == 5);
  CHECK(fit.factor == Approx(1.5).epsilon(1e-4));
  // Samples outside the image or without a surface are skipped; none usable = factor 1, samples 0.
  CHECK(fit_scene_scale(g, cam, torch::tensor({{-3.0, 2.0, 3.0}, {40.0, 2.0, 3.0}})).samples == 0);
  CHECK(fit_scene_scale(g, cam, torch::tensor({{-3.0, 2.0, 3.0}})).factor == 1.0);
  const Gaussians s = scale_about_camera(g, cam, 1.5);
  const auto in_cam = s.means + T.slice(0, 0, 3).select(1, 3);
  CHECK(torch::allclose(in_cam, cam_pts * 1.5, 1e-5, 1e-5));
  CHECK(torch::allclose(s.scales, g.scales * 1.5));
  CHECK(torch::equal(s.quats, g.quats));
  // The scaled scene renders the same image from the camera, and depth 1.5 times as far.
  const RenderOutput a = render(g, cam), b = render(s, cam);
  CHECK(torch::allclose(a.rgb, b.rgb, 1e-4, 1e-4));
  CHECK(torch::allclose(b.depth, a.depth * 1.5, 1e-4, 1e-4));
  const auto dense = depth_samples(torch::full({2, 3}, 4.0), torch::tensor({{1.0, 0.0, 1.0}, {0.0, 0.0, 1.0}}));
  CHECK(torch::equal(dense, torch::tensor({{0.5, 0.5, 4.0}, {2.5, 0.5, 4.0}, {2.5, 1.5, 4.0}})));
}

}  // namespace scale_test

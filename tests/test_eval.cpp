// Evaluation: pair selection (bins, caps, overlap and rotation filters, determinism, byte-identical
// manifests), depth-free captures (points3D and camera proxies, full-frame masks), NeRF-synthetic files, and
// a tiny end-to-end run of two methods with reports and resume.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include <opencv2/imgcodecs.hpp>

#include "core/log.h"
#include "data/nerfstudio.h"
#include "eval/evaluator.h"
#include "eval/pairs.h"
#include "io/jsonl.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

EvalDatasetOptions colmap_set(const GenerateOptions& g) {
  EvalDatasetOptions d;
  d.name = "courtyard";
  d.format = "colmap";
  d.root = generated_eval_root(g.out, "courtyard_colmap");
  return d;
}
}  // namespace

TEST_CASE("pairs: windows, filters, bins and per-scene caps", "[eval][pairs]") {
  test::QuietLogs quiet;
  auto g = test::tiny_dataset_options(test::temp_dir("pairs_data"), 24);
  g.eval_scenes = 2;
  g.train_scenes = 0;
  g.val_scenes = 0;
  g.eval_datasets = {"courtyard_colmap"};
  generate_datasets(g);
  const auto seqs = load_eval_dataset(colmap_set(g));
  REQUIRE(seqs.size() == 2);
  ProtocolOptions o;
  o.pairs_per_bin = 10;
  o.per_scene_cap = 6;
  o.seed = 5;
  const Manifest m = draw_manifest("courtyard", seqs, o);
  REQUIRE(m.bin_counts.size() == 4);
  int64_t total = 0;
  for (size_t b = 0; b < 4; ++b) {
    CHECK(m.bin_counts[b] <= 10);
    CHECK(m.bin_counts[b] <= m.bin_candidates[b]);
    total += m.bin_counts[b];
  }
  CHECK(static_cast<int64_t>(m.pairs.size()) == total);
  CHECK(m.bin_counts[0] == 10);  // small baselines are plentiful
  std::map<std::pair<std::string, int>, int> per_scene_bin;
  for (const auto& p : m.pairs) {
    CHECK(p.source != p.target);
    CHECK(std::abs(static_cast<int64_t>(p.source) - static_cast<int64_t>(p.target)) < o.window);
    CHECK(p.overlap > o.min_overlap);
    CHECK(p.rotation_deg <= o.max_rotation_deg);
    CHECK(p.baseline >= o.bin_edges[p.bin]);
    if (p.bin + 1 < 4) CHECK(p.baseline < o.bin_edges[p.bin + 1]);
    ++per_scene_bin[{p.scene, p.bin}];
  }
  for (const auto& [k, n] : per_scene_bin) CHECK(n <= 6);
  // A stricter overlap keeps fewer candidates.
  ProtocolOptions strict = o;
  strict.min_overlap = 0.95;
  const Manifest s = draw_manifest("courtyard", seqs, strict);
  CHECK(s.bin_candidates[0] < m.bin_candidates[0]);
  // Same seed: byte-identical manifest; another seed: another draw.
  const auto dir = test::temp_dir("pairs_manifest");
  write_manifest(dir + "/a.json", m);
  write_manifest(dir + "/b.json", draw_manifest("courtyard", seqs, o));
  CHECK(test::read_bytes(dir + "/a.json") == test::read_bytes(dir + "/b.json"));
  ProtocolOptions other = o;
  other.seed = 6;
  write_manifest(dir + "/c.json", draw_manifest("courtyard", seqs, other));
  CHECK(test::read_bytes(dir + "/a.json") != test::read_bytes(dir + "/c.json"));
  // The manifest reads back.
  const Manifest back = read_manifest(dir + "/a.json");
  CHECK(back.pairs.size() == m.pairs.size());
  CHECK(back.pairs[3].target_name == m.pairs[3].target_name);
  CHECK(back.bin_label(3) == "[2,inf)");
}

TEST_CASE("pairs: a generated trajectory of the default length populates all four bins", "[eval][pairs]") {
  test::QuietLogs quiet;
  auto g = test::tiny_dataset_options(test::temp_dir("pairs_bins"), 40);  // 40 frames: the default eval length
  g.train_scenes = 0;
  g.val_scenes = 0;
  g.eval_datasets = {"courtyard_colmap"};
  generate_datasets(g);
  const Manifest m = draw_manifest("courtyard", load_eval_dataset(colmap_set(g)), ProtocolOptions{});
  for (size_t b = 0; b < 4; ++b) {
    INFO("bin " << m.bin_label(static_cast<int>(b)));
    CHECK(m.bin_candidates[b] > 0);
  }
}

TEST_CASE("eval: two methods end to end, with reports and resume", "[eval]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_e2e", 16);
  // A LiDAR-variant checkpoint whose prompts come from the COLMAP points3D (an untrained tiny model).
  const std::string ck = test::temp_dir("eval_e2e_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("eval_e2e_run"), 1)).save(ck);
  EvalConfig c;
  c.datasets = {colmap_set(g)};
  c.datasets[0].prompts = "points3d";
  c.methods.push_back({"lidar", "model", ck, {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none"}});
  c.protocol.pairs_per_bin = 3;
  c.scoring.out = test::temp_dir("eval_e2e_out");
  c.scoring.weights_dir = test::project_weights_dir();
  c.scoring.lpips = {"squeeze", "alex"};
  c.scoring.examples = 1;
  Evaluator ev(c);
  const auto rows = ev.run();
  REQUIRE(rows.size() == 3 * 5);  // (4 bins + all) x (lift, identity, lidar)
  const auto all = [&](const std::string& method) {
    for (const auto& r : rows)
      if (r.method == method && r.bin == "all") return r;
    FAIL("no row for " << method);
    return ReportRow{};
  };
  const ReportRow lift = all("lift"), identity = all("identity"), lidar = all("lidar");
  CHECK(std::isfinite(lidar.psnr));
  CHECK(lidar.gaussians == 1500);
  CHECK(lift.pairs > 0);
  CHECK(lift.psnr > identity.psnr);  // lifting the source onto its depth beats copying it
  CHECK(lift.render_ms > 0);
  CHECK(std::isnan(lift.lpips.at("alex")));  // no AlexNet backbone here: reported as n/a, never made up
  CHECK(std::isfinite(lift.lpips.at("squeeze")));
  for (const char* f : {"report.md", "report.csv", "report.json", "speed_quality.png", "courtyard/manifest.json",
                        "courtyard/results_lift.jsonl", "courtyard/examples/lift_pair0.png"})
    CHECK(fs::exists(fs::path(c.scoring.out) / f));
  const std::string md = test::read_bytes(c.scoring.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("| lift | all |"));
  CHECK_THAT(md, Catch::Contains("LPIPS (alex) is n/a"));
  // Resume: a second run scores nothing new and reproduces the numbers.
  const std::string before = test::read_bytes(c.scoring.out + "/courtyard/results_lift.jsonl");
  const auto again = Evaluator(c).run();
  CHECK(test::read_bytes(c.scoring.out + "/courtyard/results_lift.jsonl") == before);
  CHECK(again[4].psnr == rows[4].psnr);
}

TEST_CASE("eval: a COLMAP capture without depth draws pairs from its points3D and scores on full frames",
          "[eval][pairs]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_nodepth", 16);
  const std::string ck = test::temp_dir("eval_nodepth_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("eval_nodepth_run"), 1)).save(ck);
  EvalDatasetOptions ds = colmap_set(g);
  ds.depth_format = "none";  // a real capture: images and a sparse model, no depth sensor
  ds.prompts = "points3d";
  const auto seqs = load_eval_dataset(ds);
  for (const auto& f : seqs.at(0).frames) REQUIRE(f.depth == DepthSource::None);
  ProtocolOptions o;
  o.pairs_per_bin = 3;
  // Without a proxy nothing could be drawn; with the points3D every source frame gets an overlap depth.
  const Manifest m = draw_manifest("courtyard", seqs, o, load_eval_points3d(ds));
  REQUIRE(!m.pairs.empty());
  CHECK(m.overlap_depth.count("points3d"));
  CHECK(!m.overlap_depth.count("dataset"));
  for (const auto& p : m.pairs) CHECK(p.overlap_depth != "dataset");
  // The overlaps agree with the ones the true depth gives, to a few per cent.
  const Manifest truth = draw_manifest("courtyard", load_eval_dataset(colmap_set(g)), o);
  CHECK(std::abs(static_cast<double>(m.bin_candidates[0]) - truth.bin_candidates[0]) <=
        0.25 * truth.bin_candidates[0] + 2);

  EvalConfig c;
  c.datasets = {ds};
  c.methods.push_back({"lidar", "model", ck, {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none"}});
  c.protocol = o;
  c.scoring.out = test::temp_dir("eval_nodepth_out");
  c.scoring.lpips = {};
  const auto rows = Evaluator(c).run();
  std::set<std::string> methods;
  for (const auto& r : rows) methods.insert(r.method);
  CHECK(methods == std::set<std::string>{"identity", "lidar"});  // lift needs depth: not scored, and said so
  for (const auto& r : rows)
    if (r.bin == "all") CHECK(std::isfinite(r.psnr));
  const std::string md = test::read_bytes(c.scoring.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("lift: not scored; the method needs the source depth"));
  CHECK_THAT(md, Catch::Contains("masks are the full frame"));
  // Full-frame masks: every scored pixel counts.
  const auto results = read_jsonl(c.scoring.out + "/courtyard/results_lidar.jsonl");
  CHECK(!results.empty());
  for (const auto& j : results) CHECK(j.at("mask_fraction").get<double>() == Approx(1.0));
}

TEST_CASE("pairs: a nerfstudio capture without depth uses the cameras, and an empty bin names its cause",
          "[eval][pairs]") {
  test::QuietLogs quiet;
  auto g = test::tiny_dataset_options(test::temp_dir("pairs_ns_nodepth"), 16);
  g.train_scenes = 0;
  g.val_scenes = 0;
  g.eval_datasets = {"atrium_nerfstudio"};
  generate_datasets(g);
  const std::string scene_root = generated_eval_root(g.out, "atrium_nerfstudio");
  std::string scene;
  for (const auto& e : fs::directory_iterator(scene_root)) scene = e.path().string();
  nlohmann::json t = nlohmann::json::parse(test::read_bytes(scene + "/transforms.json"));
  for (auto& f : t["frames"]) f.erase("depth_file_path");
  test::write_bytes(scene + "/transforms.json", t.dump());
  EvalDatasetOptions ds;
  ds.name = "atrium";
  ds.format = "nerfstudio";
  ds.root = scene_root;
  const auto seqs = load_eval_dataset(ds);
  ProtocolOptions o;
  o.pairs_per_bin = 4;
  o.fallback_depth = 4.0;
  const Manifest fixed = draw_manifest("atrium", seqs, o);
  REQUIRE(!fixed.pairs.empty());
  CHECK(fixed.overlap_depth.count("fixed"));
  o.fallback_depth = 0;  // from the cameras: where neighbouring optical axes converge
  const Manifest axes = draw_manifest("atrium", seqs, o);
  CHECK(!axes.pairs.empty());
  CHECK(axes.overlap_depth.count("camera-axes"));
  // A bin beyond every baseline: the reason says so, not the overlap filter.
  o.bin_edges = {0.0, 1000.0};
  const Manifest far = draw_manifest("atrium", seqs, o);
  CHECK(far.bin_counts.at(1) == 0);
  CHECK_THAT(far.shortfall_reason(1), Catch::Contains("No pair that passes the filters has a baseline in [1000,inf)"));
}

TEST_CASE("nerfstudio: NeRF-synthetic files (camera_angle_x, no size, no extension) are read", "[eval][data]") {
  test::QuietLogs quiet;
  const std::string dir = test::temp_dir("nerf_synthetic");
  fs::create_directories(dir + "/train");
  const cv::Mat img(48, 64, CV_8UC3, cv::Scalar(10, 120, 200));
  for (int i = 0; i < 3; ++i) cv::imwrite(dir + "/train/r_" + std::to_string(i) + ".png", img);
  nlohmann::json t = {{"camera_angle_x", 0.6911112070083618}, {"frames", nlohmann::json::array()}};
  for (int i = 0; i < 3; ++i)
    t["frames"].push_back({{"file_path", "./train/r_" + std::to_string(i)},
                           {"rotation", 0.0126},
                           {"transform_matrix", {{1, 0, 0, 0.1 * i}, {0, 1, 0, 0}, {0, 0, 1, 4}, {0, 0, 0, 1}}}});
  test::write_bytes(dir + "/transforms_train.json", t.dump());
  const Sequence s = nerfstudio_sequence(dir, "blender", "transforms_train.json");
  REQUIRE(s.frames.size() == 3);
  const Intrinsics& k = s.frames[0].view.intr;
  CHECK(k.width == 64);
  CHECK(k.height == 48);
  CHECK(k.fx == Approx(0.5 * 64 / std::tan(0.5 * 0.6911112070083618)));
  CHECK(k.fy == Approx(k.fx));
  CHECK(s.frames[2].image_path.size() > 4);
  CHECK(s.frames[2].image_path.substr(s.frames[2].image_path.size() - 4) == ".png");
  // A broken angle names the file and the key.
  t["camera_angle_x"] = -1;
  test::write_bytes(dir + "/transforms_bad.json", t.dump());
  CHECK_THROWS_WITH(nerfstudio_sequence(dir, "blender", "transforms_bad.json"), Catch::Contains("camera_angle_x"));
}

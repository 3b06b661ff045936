// Evaluation: pair selection (bins, caps, overlap and rotation filters, determinism, byte-identical
// manifests), depth-free captures (points3D and camera proxies, full-frame masks), NeRF-synthetic files, and
// a tiny end-to-end run of two methods with reports and resume, and a support-budget sweep with pruning.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>

#include <opencv2/imgcodecs.hpp>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "data/nerfstudio.h"
#include "data/perturb.h"
#include "eval/evaluator.h"
#include "eval/pairs.h"
#include "eval/results_log.h"
#include "geometry/color.h"
#include "io/atomic_file.h"
#include "io/jsonl.h"
#include "metrics/metrics.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("pairs: windows, filters, bins and per-scene caps", "[eval][pairs]") {
  test::QuietLogs quiet;
  auto g = test::eval_dataset_options(test::temp_dir("pairs_data"), 24, {"courtyard_colmap"});
  g.eval_scenes = 2;
  generate_datasets(g);
  const auto seqs = load_eval_dataset(test::tiny_courtyard_set(g));
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
  auto g = test::eval_dataset_options(test::temp_dir("pairs_bins"), 40,
                                      {"courtyard_colmap"});  // 40 frames: the default eval length
  generate_datasets(g);
  const Manifest m = draw_manifest("courtyard", load_eval_dataset(test::tiny_courtyard_set(g)), ProtocolOptions{});
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
  c.datasets = {test::tiny_courtyard_set(g)};
  c.datasets[0].prompts = "points3d";
  c.methods.push_back(
      named_method("lidar", "model", ck, {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none"}));
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
      if (r.method.label() == method && r.bin == "all") return r;
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
  if (test::project_weights_dir().empty())
    CHECK(std::isnan(lift.lpips.at("squeeze")));  // no weights found: n/a as well (core/weights.h)
  else
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
  // The stamp holds the checkpoint's fingerprint; an older stamp without one adopts it.
  const std::string stamp = c.scoring.out + "/courtyard/results_lidar.jsonl.method.json";
  auto js = nlohmann::json::parse(test::read_bytes(stamp));
  CHECK(js.value("checkpoint_fingerprint", "") == file_fingerprint(ck));
  js.erase("checkpoint_fingerprint");
  write_file_atomic(stamp, js.dump());
  Evaluator(c).run();
  CHECK(nlohmann::json::parse(test::read_bytes(stamp)).value("checkpoint_fingerprint", "") == file_fingerprint(ck));
  // A stamp written before an option existed adopts that option's default, and only its default.
  js = nlohmann::json::parse(test::read_bytes(stamp));
  REQUIRE(js["perturb"].contains("depth_warp"));
  js["perturb"].erase("depth_warp");
  write_file_atomic(stamp, js.dump());
  Evaluator(c).run();
  CHECK(nlohmann::json::parse(test::read_bytes(stamp))["perturb"].value("depth_warp", -1.0) == 0.0);
  js["perturb"].erase("depth_warp");
  write_file_atomic(stamp, js.dump());
  EvalConfig warped = c;
  for (auto& m : warped.methods)
    if (m.name == "lidar") m.perturb.depth_warp = 0.1;
  CHECK_THROWS_WITH(Evaluator(warped).run(), Catch::Contains("was scored with other options for method 'lidar'"));
  // Other weights at the same path (a retrained model) never resume the old scores.
  TrainConfig other = test::tiny_train_config(g, test::temp_dir("eval_e2e_run2"), 1);
  other.runtime.seed = 7;
  Trainer(other).save(ck);
  CHECK_THROWS_WITH(Evaluator(c).run(), Catch::Contains("was scored with other weights for method 'lidar'"));
  // A missing checkpoint fails before any method is scored, naming the method and the file.
  EvalConfig missing = c;
  missing.scoring.out = test::temp_dir("eval_e2e_missing");
  missing.methods.push_back(named_method("later", "model", ck + ".absent", {}));
  CHECK_THROWS_WITH(Evaluator(missing).run(),
                    Catch::Contains("method 'later'") && Catch::Contains("tiny.safetensors.absent: no such file"));
  CHECK_FALSE(fs::exists(missing.scoring.out + "/courtyard/results_lift.jsonl"));
  // A checkpoint of a run that has not finished (no summary.json beside its checkpoints/) is scored, and the report
  // says so.
  const std::string run = test::temp_dir("eval_e2e_unfinished");
  fs::create_directories(run + "/checkpoints");
  fs::copy_file(ck, run + "/checkpoints/last.safetensors", fs::copy_options::overwrite_existing);
  write_file_atomic(run + "/config.json", "{}");
  EvalConfig unfinished = c;
  unfinished.scoring.out = test::temp_dir("eval_e2e_unfinished_out");
  unfinished.methods.back().checkpoint = run + "/checkpoints/last.safetensors";
  Evaluator(unfinished).run();
  CHECK_THAT(test::read_bytes(unfinished.scoring.out + "/report.md"),
             Catch::Contains("is from a run that has not finished"));
}

TEST_CASE("eval: display factors score each target again at k times its size, for the methods that render",
          "[eval][display]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_display", 16);
  EvalConfig c;
  c.datasets = {test::tiny_courtyard_set(g)};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("eval_display_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  c.scoring.display_factors = {2, 4};
  const auto rows = Evaluator(c).run();
  const auto all = [&](const std::string& method) {
    for (const auto& r : rows)
      if (r.method.label() == method && r.bin == "all") return r;
    FAIL("no row for " << method);
    return ReportRow{};
  };
  // lift renders one Gaussian per source pixel: a pixel's footprint covers its pixel at the working size, and gaps
  // open between them at 4x, more than at 2x; identity has no scene to render again.
  const ReportRow lift = all("lift"), identity = all("identity");
  REQUIRE(lift.display.size() == 2);
  const DisplayScore x2 = lift.display.at(2.0), x4 = lift.display.at(4.0);
  CHECK(std::isfinite(x2.psnr));
  CHECK(std::isfinite(x4.psnr));
  CHECK(x4.hole_rate > x2.hole_rate);
  CHECK(x2.hole_rate >= lift.hole_rate);
  CHECK(identity.display.empty());
  // Each record carries its factors; the report has the table; the stamp holds the factors, so other factors
  // never resume these scores.
  const std::string log = test::read_bytes(c.scoring.out + "/courtyard/results_lift.jsonl");
  const auto first = nlohmann::json::parse(log.substr(0, log.find('\n')));
  REQUIRE(first.at("display").size() == 2);
  CHECK(first.at("display")[1].at("factor") == 4.0);
  CHECK(result_from_json(first).display.at(1).hole_rate == first.at("display")[1].at("hole_rate").get<double>());
  CHECK_THAT(test::read_bytes(c.scoring.out + "/report.md"),
             Catch::Contains("At display resolution") && Catch::Contains("holes % at 4x"));
  EvalConfig other = c;
  other.scoring.display_factors = {3};
  CHECK_THROWS_WITH(Evaluator(other).run(), Catch::Contains("was scored with other options"));
  other.scoring.display_factors = {9};
  CHECK_THROWS_WITH(config_from_json<EvalConfig>(config_to_json(other), "eval.json"),
                    Catch::Contains("display_factors"));
  // A damaged factor in the log is named.
  auto bad = first;
  bad["display"][0]["factor"] = 0.5;
  CHECK_THROWS_WITH(result_from_json(bad), Catch::Contains("display.factor"));
}

TEST_CASE("eval: budget sweeps expand into one method per budget, and bad budgets name themselves", "[eval]") {
  MethodOptions m = named_method("full", "model", "ck.safetensors", {"prior.type=dataset"});
  m.budgets = {"px:0.5", "n:50000", "detail:1"};
  const auto out = expand_sweeps({named_method("lift", "lift"), m});
  REQUIRE(out.size() == 4);
  CHECK(out[0].name == "lift");
  CHECK(out[1].name == "full");  // the budget is a field, not a suffix of the name
  CHECK(out[1].sweep == SweepPoint{"", "px", 0.5});
  CHECK(out[1].label() == "full@px0.5");
  CHECK(out[2].sweep == SweepPoint{"", "n", 50000});
  CHECK(out[2].label() == "full@n50000");
  CHECK(out[1].overrides ==
        std::vector<std::string>{"prior.type=dataset", "sampler.budget_mode=per_pixel", "sampler.density=0.5"});
  CHECK(out[2].overrides.back() == "sampler.budget=50000");
  CHECK(out[3].overrides[1] == "sampler.budget_mode=detail");
  for (const char* bad : {"px", "px:", "px:-1", "px:0.5x", "budget:3"}) {
    m.budgets = {bad};
    CHECK_THROWS_WITH(expand_sweeps({m}), Catch::Contains(std::string("budget '") + bad + "'"));
  }
  m.budgets = {"px:1", "px:1"};
  CHECK_THROWS_WITH(expand_sweeps({m}), Catch::Contains("two methods are named 'full@px1'"));
  // Different names that map to one results file (@ becomes _) are refused too, naming both.
  EvalDatasetOptions rooms, rooms_again;
  rooms.name = "rooms held-out", rooms_again.name = "rooms_held-out";
  CHECK_NOTHROW(check_dataset_names({rooms}));
  CHECK_THROWS_WITH(check_dataset_names({rooms, rooms_again}),
                    Catch::Contains("datasets 'rooms held-out' and 'rooms_held-out' would share the output folder"));
  CHECK_THROWS_WITH(check_dataset_names({}), Catch::Contains("no datasets"));
  m.budgets = {"px:1"};
  CHECK_THROWS_WITH(expand_sweeps({m, named_method("full_px1", "lift")}),
                    Catch::Contains("methods 'full@px1' and 'full_px1' would share the results file results_full_px1"));
  CHECK((MethodId{"full", {"", "px", 0.25}}.family()) == "full px");
  CHECK((MethodId{"full+prune", {"", "detail", 2}}.family()) == "full+prune detail");
  CHECK((MethodId{"lift", {}}.family()) == "lift");
  CHECK((MethodId{"full", {"", "n", 1e6}}.label()) == "full@n1000000");
  // Cheaper and better points form the front; dominated ones do not.
  const std::vector<std::pair<double, double>> pts = {{10, 20}, {5, 21}, {20, 22}, {30, 21.5}, {20, 19}, {1, 15}};
  CHECK(pareto_front(pts) == std::vector<size_t>{5, 1, 2});
  // No method family is drawn like the front (the eighth family used to get its grey crosses).
  for (size_t k = 0; k < 40; ++k) CHECK(family_style(k).first != kParetoColor);
  CHECK(family_style(0) != family_style(1));
  // Paired differences: a method 1 dB better on every shared pair, with half the Gaussians.
  ScoredMethods res;
  for (int64_t i = 0; i < 20; ++i) {
    PairResult r;
    r.index = i, r.psnr = 20 + 0.1 * static_cast<double>(i), r.gaussians = 1000, r.lpips["squeeze"] = 0.2;
    r.bin = static_cast<int>(i % 2), r.hole_rate = 0.01, r.crack_rate = 0.02;
    res[{"ref", {}}].push_back(r);
    r.psnr += 1.0, r.gaussians = 500, r.hole_rate = r.bin == 1 ? 0.03 : 0.01;
    if (i != 3) res[{"better", {}}].push_back(r);  // one pair missing: only shared pairs count
  }
  const auto d = paired_differences("set", "ref", res, "squeeze");
  REQUIRE(d.size() == 1);
  CHECK(d[0].method.label() == "better");
  CHECK(d[0].psnr.n == 19);
  CHECK(d[0].psnr.mean == Approx(1.0));
  CHECK(d[0].psnr.excludes_zero());
  CHECK_FALSE(d[0].lpips.excludes_zero());
  CHECK(d[0].gaussians == Approx(0.5));
  CHECK_FALSE(d[0].cracks.excludes_zero());  // equal crack rates
  CHECK(d[0].cracks.mean == Approx(0.0));
  CHECK(paired_differences("set", "absent", res, "squeeze").empty());
  // Per bin: the hole rate differs only in bin 1, by 2 percentage points.
  const auto per_bin = paired_differences("set", "ref", res, "squeeze", 500, {"near", "far"});
  REQUIRE(per_bin.size() == 3);
  CHECK(per_bin[0].bin == "all");
  CHECK(per_bin[1].bin == "near");
  CHECK(per_bin[1].psnr.n == 10);  // even indices 0..18
  CHECK(per_bin[2].psnr.n == 9);   // odd indices without the missing pair 3
  CHECK(per_bin[1].holes.mean == Approx(0.0));
  CHECK(per_bin[2].bin == "far");
  CHECK(per_bin[2].holes.mean == Approx(2.0));
  CHECK(per_bin[2].holes.excludes_zero());

  // Sweep slopes over pairs: PSNR falls 0.5 dB per % of noise on every pair (plus pair-specific jitter that
  // does not trend), is flat under blur, and the pair one point missed is left out.
  ScoredMethods sweeps;
  for (int64_t i = 0; i < 30; ++i)
    for (double noise : {0.0, 0.01, 0.02, 0.05}) {
      PairResult r;
      r.index = i;
      r.psnr = 25 + 0.2 * static_cast<double>(i % 3) - 50 * noise + 0.3 * std::sin(7.0 * i + 100 * noise);
      if (!(i == 4 && noise == 0.02)) sweeps[{"lidar", {"override:prior.sparse.noise", "", noise}}].push_back(r);
    }
  for (int64_t i = 0; i < 30; ++i)
    for (double px : {2.0, 4.0}) {
      PairResult r;
      r.index = i, r.psnr = 24 + 0.4 * ((i + static_cast<int64_t>(px)) % 2 ? 1 : -1);
      sweeps[{"full", {"perturb.depth_blur_px", "", px}}].push_back(r);
      r.psnr = 24;  // unperturbed: the 0 px point
      if (px == 2.0) sweeps[{"full", {}}].push_back(r);
    }
  const auto slopes = sweep_slopes("set", sweeps);
  REQUIRE(slopes.size() == 2);
  const auto noise = std::find_if(slopes.begin(), slopes.end(), [](auto& s) { return s.family == "lidar noise"; });
  REQUIRE(noise != slopes.end());
  CHECK(noise->unit == "%");
  CHECK(noise->slope.n == 29);
  CHECK(noise->slope.mean == Approx(-0.5).margin(0.05));
  CHECK(noise->slope.hi < 0);
  const auto blur =
      std::find_if(slopes.begin(), slopes.end(), [](auto& s) { return s.family == "full depth_blur_px"; });
  REQUIRE(blur != slopes.end());
  CHECK(blur->slope.n == 30);
  CHECK(blur->slope.lo < 0);  // no trend: the interval holds 0
  CHECK(blur->slope.hi > 0);
  // The report's sweep table puts the paper's Table 4 slope beside the LiDAR noise sweep only.
  std::vector<ReportRow> rows;
  for (const auto& [method, res] : sweeps)
    for (const ReportRow& r : summarize("set", method, {}, {}, res, {})) rows.push_back(r);
  const std::string report_dir = test::temp_dir("eval_slopes_report");
  write_reports(report_dir, rows, {}, {}, {}, {}, slopes);
  const std::string md = test::read_bytes(report_dir + "/report.md");
  const size_t lidar = md.find("| lidar noise | "), blur_row = md.find("| full depth_blur_px | ");
  REQUIRE(lidar != std::string::npos);
  REQUIRE(blur_row != std::string::npos);
  CHECK_THAT(md.substr(lidar, md.find('\n', lidar) - lidar),
             Catch::EndsWith(" | -0.46 dB per % (Table 4: ETH3D, 25.9 -> 23.6 dB from 0 to 5%) |"));
  CHECK_THAT(md.substr(blur_row, md.find('\n', blur_row) - blur_row), Catch::EndsWith(" | - |"));
}

TEST_CASE("eval: perturbations have the requested strength, are deterministic, and sweep by key", "[eval]") {
  const int64_t H = 48, W = 64;
  ViewTensors v;
  torch::manual_seed(1);
  v.image = torch::rand({3, H, W});
  v.depth = torch::full({H, W}, 4.0f);
  v.depth.narrow(1, 32, 32).fill_(2.0f);  // one vertical depth edge between columns 31 and 32
  v.valid = torch::ones({H, W});
  const int64_t edge_pixels = 2 * H;
  CHECK(depth_edges(v.depth, v.valid).sum().item<int64_t>() == edge_pixels);

  PerturbOptions o;
  CHECK_FALSE(o.any());
  CHECK(torch::equal(perturb_source(v, o, 3).depth, v.depth));
  o.depth_noise = 0.03;
  const ViewTensors a = perturb_source(v, o, 3), b = perturb_source(v, o, 3), c = perturb_source(v, o, 4);
  CHECK(torch::equal(a.depth, b.depth));  // same seed, same perturbation
  CHECK_FALSE(torch::equal(a.depth, c.depth));
  const double sigma = (a.depth / v.depth - 1).std().item<double>();
  CHECK(sigma == Approx(0.03).epsilon(0.05));  // 3072 samples: the estimate is within 5%
  CHECK(torch::equal(a.image, v.image));

  o = PerturbOptions{};
  o.depth_holes = 0.3;
  const ViewTensors h = perturb_source(v, o, 5);
  CHECK(h.valid.sum().item<int64_t>() == H * W - std::llround(0.3 * H * W));  // exactly the requested share
  CHECK((h.depth * (1 - h.valid)).abs().sum().item<double>() == 0);
  // Blobs by default: a hole pixel's right neighbour is far more often a hole than for independent pixels.
  auto clustered = [&](const torch::Tensor& valid) {
    const auto hole = valid < 0.5, left = hole.narrow(1, 0, W - 1), right = hole.narrow(1, 1, W - 1);
    return left.logical_and(right).sum().item<double>() / left.sum().item<double>();
  };
  CHECK(clustered(h.valid) > 0.8);
  o.depth_hole_size = 0;
  const ViewTensors scattered = perturb_source(v, o, 5);
  CHECK(scattered.valid.sum().item<int64_t>() == h.valid.sum().item<int64_t>());
  CHECK(clustered(scattered.valid) < 0.45);

  o = PerturbOptions{};
  o.depth_scale = 1.3;
  CHECK(torch::allclose(perturb_source(v, o, 0).depth, v.depth * 1.3));
  o.depth_scale = 1.0;
  o.depth_side = "left";
  const ViewTensors left = perturb_source(v, o, 0);
  CHECK(left.valid.narrow(1, 0, 32).min().item<float>() == 1.0f);
  CHECK(left.valid.narrow(1, 32, 32).max().item<float>() == 0.0f);

  o = PerturbOptions{};
  o.depth_edge_noise = 0.1;
  const auto moved = (perturb_source(v, o, 2).depth != v.depth).to(torch::kFloat32);
  CHECK(moved.sum().item<int64_t>() == edge_pixels);  // only the edge pixels change
  {  // ... by the requested sigma: on stripes 8 px wide, 39 edges of 2 x 48 pixels, within 10%
    ViewTensors stripes;
    const auto column = torch::arange(320).to(torch::kFloat32);
    stripes.depth = (3.0f + (column / 8).floor().remainder(2)).view({1, 320}).expand({H, 320}).contiguous();
    stripes.valid = torch::ones({H, 320});
    stripes.image = torch::rand({3, H, 320});
    const auto edges = depth_edges(stripes.depth, stripes.valid) > 0;
    const auto ratio = perturb_source(stripes, o, 2).depth / stripes.depth - 1;
    CHECK(ratio.masked_select(edges).std().item<double>() == Approx(0.1).epsilon(0.1));
    CHECK(ratio.masked_select(edges.logical_not()).abs().max().item<double>() == 0.0);
  }
  {  // every random perturbation is a function of its seed: the same seed repeats it, another seed changes it
    std::vector<PerturbOptions> random(4);
    random[0].depth_noise = 0.02;
    random[1].depth_edge_noise = 0.1;
    random[2].depth_holes = 0.2;                                 // blobs
    random[3].depth_holes = 0.2, random[3].depth_hole_size = 0;  // scattered pixels
    for (size_t k = 0; k < random.size(); ++k) {
      INFO("random perturbation " << k);
      const ViewTensors one = perturb_source(v, random[k], 21), again = perturb_source(v, random[k], 21),
                        other = perturb_source(v, random[k], 22);
      CHECK(torch::equal(one.depth, again.depth));
      CHECK(torch::equal(one.valid, again.valid));
      CHECK_FALSE((torch::equal(one.depth, other.depth) && torch::equal(one.valid, other.valid)));
    }
  }
  o = PerturbOptions{};
  o.depth_edge_holes = 2;
  const ViewTensors dropped = perturb_source(v, o, 0);
  CHECK(dropped.valid.sum().item<int64_t>() == H * W - 6 * H);  // columns 29..34: within 2 of columns 31, 32
  CHECK(dropped.valid.narrow(1, 29, 6).max().item<float>() == 0.0f);
  CHECK(dropped.valid.narrow(1, 0, 29).min().item<float>() == 1.0f);
  CHECK(dropped.valid.narrow(1, 35, 29).min().item<float>() == 1.0f);
  CHECK(torch::equal(dropped.depth, v.depth * dropped.valid));  // kept depth is untouched, dropped depth is 0
  ViewTensors bump = v;  // one pixel nearer: its edge is a cross of 5 pixels, grown by 1 to 5x5 minus the corners
  bump.depth = torch::full({H, W}, 4.0f);
  bump.depth[20][10] = 3.0f;
  o.depth_edge_holes = 1;
  CHECK(perturb_source(bump, o, 0).valid.sum().item<int64_t>() == H * W - 21);  // a city-block band would drop 13
  o.depth_edge_holes_side = "far";  // the far side only: the bump's 20 neighbours lose their depth, it keeps its own
  const ViewTensors shadow = perturb_source(bump, o, 0);
  CHECK(shadow.valid.sum().item<int64_t>() == H * W - 20);
  CHECK(shadow.valid[20][10].item<float>() == 1.0f);
  o.depth_edge_holes = 2;  // on the step, the far half of the two-sided band: columns 29..31, not 32..34
  const ViewTensors far = perturb_source(v, o, 0);
  CHECK(far.valid.sum().item<int64_t>() == H * W - 3 * H);
  CHECK(far.valid.narrow(1, 29, 3).max().item<float>() == 0.0f);
  CHECK(far.valid.narrow(1, 32, 32).min().item<float>() == 1.0f);
  CHECK(far.valid.narrow(1, 0, 29).min().item<float>() == 1.0f);
  CHECK_THROWS_AS(config_from_json<PerturbOptions>({{"depth_edge_holes_side", "near"}}, "test"), Error);
  o = PerturbOptions{};
  o.depth_blur_px = 3;
  const auto blurred = perturb_source(v, o, 0).depth;
  CHECK(blurred[10][5].item<float>() == Approx(4.0f));  // flat regions keep their depth
  CHECK(blurred[10][31].item<float>() < 3.9f);          // the edge is smeared
  CHECK(blurred[10][31].item<float>() > 2.1f);

  o = PerturbOptions{};
  o.exposure = 2.0;
  const auto bright = perturb_source(v, o, 0).image;
  CHECK(bright.mean().item<double>() > v.image.mean().item<double>());
  {  // exactly twice the light where it does not clip
    const auto lin = srgb_to_linear(v.image), lin_bright = srgb_to_linear(bright), unclipped = lin < 0.45;
    REQUIRE(unclipped.sum().item<int64_t>() > 1000);
    REQUIRE((lin > 0.5).sum().item<int64_t>() > 1000);
    CHECK(torch::allclose(lin_bright.masked_select(unclipped), 2 * lin.masked_select(unclipped), 1e-4, 1e-6));
    CHECK(lin_bright.masked_select(lin > 0.5).min().item<float>() == 1.0f);
  }
  o.exposure = 1.0;
  o.jpeg_quality = 10;
  ViewTensors smooth = v;  // JPEG keeps smooth content well at high quality (noise it cannot)
  const auto ramp = torch::linspace(0, 1, W).view({1, 1, W}).expand({3, H, W});
  smooth.image = (0.5 + 0.4 * torch::sin(12 * ramp + torch::linspace(0, 3, H).view({1, H, 1}))).contiguous();
  const double q10 = psnr(perturb_source(smooth, o, 0).image, smooth.image);
  o.jpeg_quality = 95;
  const double q95 = psnr(perturb_source(smooth, o, 0).image, smooth.image);
  CHECK(q95 > q10 + 3);

  MethodOptions m = named_method("full", "model", "ck.safetensors");
  m.sweep_key = "perturb.depth_noise";
  m.sweep_values = {0, 0.02};
  const auto out = expand_sweeps({m});
  REQUIRE(out.size() == 2);
  CHECK(out[0].name == "full");  // the swept key and value are fields, not a suffix of the name
  CHECK(out[0].label() == "full~depth_noise0");
  CHECK(out[1].label() == "full~depth_noise0.02");
  CHECK(out[1].perturb.depth_noise == 0.02);
  CHECK(out[1].sweep_key.empty());
  CHECK(out[1].sweep == SweepPoint{"perturb.depth_noise", "", 0.02});
  CHECK(out[1].id().family() == "full depth_noise");
  m.sweep_key = "perturb.jpeg_quality";
  m.sweep_values = {90};
  CHECK(expand_sweeps({m})[0].perturb.jpeg_quality == 90);
  m.sweep_key = "override:prior.sparse.prompts";  // a model config key goes through the overrides
  m.sweep_values = {500, 20};
  const auto prompts = expand_sweeps({m});
  REQUIRE(prompts.size() == 2);
  CHECK(prompts[1].label() == "full~prompts20");
  CHECK(prompts[1].overrides.back() == "prior.sparse.prompts=20");
  CHECK(prompts[0].sweep.value == 500);
  // The same depth options act on a prior's output map as on the source view's depth.
  o = PerturbOptions{};
  o.depth_holes = 0.5;
  CHECK(o.any_depth());
  const PerturbedDepth holed = perturb_depth(v.depth, v.valid, o, 9);
  CHECK(torch::equal(holed.valid, perturb_source(v, o, 9).valid));
  // Prompts given directly: noise on z, holes drop that share, a side keeps only its half.
  const auto given = torch::stack(
      {torch::arange(100).to(torch::kFloat32) * 0.64f, torch::full({100}, 10.0f), torch::full({100}, 5.0f)}, 1);
  CHECK(torch::equal(perturb_prompts(given, PerturbOptions{}, 1, W, H), given));
  CHECK(perturb_prompts(given, o, 1, W, H).size(0) == 50);
  o = PerturbOptions{};
  o.depth_side = "left";
  CHECK(perturb_prompts(given, o, 1, W, H).size(0) == 50);  // u < 32
  o = PerturbOptions{};
  o.depth_noise = 0.05;
  const auto noisy = perturb_prompts(given, o, 1, W, H);
  CHECK((noisy.select(1, 2) / 5 - 1).std().item<double>() == Approx(0.05).epsilon(0.3));
  CHECK(torch::equal(noisy.narrow(1, 0, 2), given.narrow(1, 0, 2)));
  o = PerturbOptions{};
  o.exposure = 1.5;
  CHECK_FALSE(o.any_depth());
  m.sweep_key.clear();  // values without a key, a sweep beside budgets, depth perturbations of identity
  m.sweep_values = {0.1};
  CHECK_THROWS_WITH(expand_sweeps({m}), Catch::Contains("sweep_key is empty"));
  m.sweep_key = "perturb.depth_noise";
  m.budgets = {"px:1"};
  CHECK_THROWS_WITH(expand_sweeps({m}), Catch::Contains("a value sweep and budgets"));
  m.budgets.clear();
  MethodOptions idm = named_method("id", "identity");
  idm.perturb.depth_scale = 1.2;
  CHECK_THROWS_WITH(expand_sweeps({idm}), Catch::Contains("identity uses no depth"));
  m.sweep_key = "perturb.jpeg_quality";  // an integer option names the rounded value
  m.sweep_values = {30.4};
  CHECK(expand_sweeps({m})[0].label() == "full~jpeg_quality30");
  m.sweep_key = "perturb.no_such_key";
  CHECK_THROWS_WITH(expand_sweeps({m}), Catch::Contains("sweep_key 'perturb.no_such_key'"));
  m.sweep_key = "perturb.depth_noise";
  m.sweep_values = {2.0};  // outside the option's range
  CHECK_THROWS_AS(expand_sweeps({m}), Error);
}

TEST_CASE("eval: motion types and the finer baseline breakdown", "[eval]") {
  // From cameras (T_cw world-to-camera): the source at the origin looking down +z, fx = W/2 (90° FOV).
  ViewTensors src, tgt;
  src.image = torch::zeros({3, 8, 16});
  src.depth = torch::full({8, 16}, 4.0f);
  src.valid = torch::ones({8, 16});
  src.camera.K = torch::tensor({{8.0f, 0.0f, 8.0f}, {0.0f, 8.0f, 4.0f}, {0.0f, 0.0f, 1.0f}});
  src.camera.T_cw = torch::eye(4);
  tgt = src;
  auto moved_to = [&](float x, float y, float z) {  // target centre at (x, y, z), same orientation
    tgt.camera.T_cw = torch::eye(4);
    tgt.camera.T_cw.index_put_({torch::indexing::Slice(0, 3), 3}, torch::tensor({-x, -y, -z}));
    return pair_motion(src, tgt, torch::Tensor());
  };
  CHECK(moved_to(0.5f, 0.0f, 0.1f) == "lateral");
  CHECK(moved_to(0.0f, 0.1f, 1.0f) == "forward");       // 0.25 · 1 / 4 against 0.1 / 4
  const float c = std::cos(0.3f), sn = std::sin(0.3f);  // a 0.3 rad yaw in place
  tgt.camera.T_cw = torch::eye(4);
  tgt.camera.T_cw.index_put_({torch::indexing::Slice(0, 3), torch::indexing::Slice(0, 3)},
                             torch::tensor({{c, 0.0f, -sn}, {0.0f, 1.0f, 0.0f}, {sn, 0.0f, c}}));
  CHECK(pair_motion(src, tgt, torch::Tensor()) == "rotation");
  src.valid.zero_();  // no depth and no prompts: unknown; with prompts their depth is used
  CHECK(pair_motion(src, tgt, torch::Tensor()).empty());
  CHECK(moved_to(0.5f, 0.0f, 0.0f) == "");
  CHECK(pair_motion(src, tgt, torch::tensor({{1.0f, 1.0f, 4.0f}, {2.0f, 2.0f, 4.0f}, {3.0f, 3.0f, 4.0f}})) ==
        "lateral");
  CHECK(motion_type({0.8, 0.1, 0.2}, 2.0, 4.0) == "lateral");
  CHECK(motion_type({0.1, 0.0, 1.5}, 2.0, 4.0) == "forward");     // 0.5 * 1.5 / 4 > 0.1 / 4
  CHECK(motion_type({0.05, 0.0, 0.0}, 20.0, 2.0) == "rotation");  // 0.35 rad against 0.025
  CHECK_THROWS_AS(motion_type({1, 0, 0}, 0.0, 0.0), Error);
  std::vector<PairResult> results(4);
  const double baselines[4] = {0.2, 0.7, 0.8, 2.6}, psnrs[4] = {30, 24, 20, 15};
  const char* motions[4] = {"lateral", "forward", "lateral", "rotation"};
  for (int k = 0; k < 4; ++k) {
    results[k].index = k, results[k].baseline = baselines[k], results[k].psnr = psnrs[k];
    results[k].motion = motions[k];
  }
  std::map<std::string, ReportRow> by;
  for (const auto& r : breakdown("set", {"m", {}}, results, {}, 0.5)) by[r.bin] = r;
  REQUIRE(by.size() == 6);  // 3 baseline groups with pairs (of 6) and 3 motion types
  CHECK(by.at("baseline [0,0.5)").pairs == 1);
  CHECK(by.at("baseline [0.5,1)").pairs == 2);
  CHECK(by.at("baseline [0.5,1)").psnr == Approx(22));
  CHECK(by.at("baseline [2.5,3)").psnr == Approx(15));
  CHECK(by.count("baseline [1,1.5)") == 0);  // empty groups are left out
  CHECK(by.at("motion lateral").pairs == 2);
  CHECK(by.at("motion lateral").psnr == Approx(25));
  CHECK(by.at("motion rotation").psnr == Approx(15));
  CHECK_THROWS_AS(breakdown("set", {"m", {}}, results, {}, 0.0), Error);

  // A sweep without its neutral value takes the unperturbed run of the same method as that point.
  std::vector<ReportRow> rows;
  for (const auto& [point, value] :
       std::vector<std::pair<SweepPoint, double>>{{{}, 30},
                                                  {{"perturb.depth_holes", "", 0.2}, 25},
                                                  {{"perturb.depth_holes", "", 0.4}, 20},
                                                  {{"perturb.depth_noise", "", 0.01}, 29},
                                                  {{"perturb.depth_scale", "", 0.8}, 26},
                                                  {{"perturb.depth_scale", "", 1.25}, 26}}) {
    ReportRow r;
    r.dataset = "set", r.method = {"m", point}, r.bin = "all", r.pairs = 1, r.psnr = value;
    rows.push_back(r);
  }
  const std::string out = test::temp_dir("eval_slopes");
  write_reports(out, rows, {}, {});
  const std::string md = test::read_bytes(out + "/report.md");
  CHECK_THAT(md,
             Catch::Contains("| m depth_holes | 0, 0.2, 0.4 | 30.00, 25.00, 20.00 | -0.250 dB per % | n/a | falls |"));
  CHECK_THAT(md, Catch::Contains("| m depth_noise | 0, 0.01 | 30.00, 29.00 | -1.000 dB per % | n/a | falls |"));
  // Two-sided: a scale off by x0.8 or x1.25 is equally strong (|ln value|).
  CHECK_THAT(md, Catch::Contains("| m depth_scale | 0.8, 1, 1.25 | 26.00, 30.00, 26.00 | -17.926 dB per unit of abs(ln "
                                 "value) | n/a | falls |"));
  CHECK(fs::exists(fs::path(out) / "stability.png"));
}

TEST_CASE("eval: a budget sweep of a checkpoint in pixel mode (the default model) is refused, naming the fix",
          "[eval]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_sweep_pixel", 16);
  const std::string ck = test::temp_dir("eval_sweep_pixel_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("eval_sweep_pixel_run"), 1, test::tiny_default_options())).save(ck);
  EvalConfig c;
  c.datasets = {test::tiny_courtyard_set(g)};
  c.methods = {named_method("tiny", "model", ck, {"prior.type=dataset"})};
  c.methods[0].budgets = {"n:700"};
  c.protocol.pairs_per_bin = 1;
  c.scoring.out = test::temp_dir("eval_sweep_pixel_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  CHECK_THROWS_WITH(Evaluator(c).run(), Catch::Contains("method 'tiny': budgets sweep the support budget") &&
                                            Catch::Contains("pixel mode") &&
                                            Catch::Contains("sampler.mode=area and sampler.edge_supports=true"));
  c.methods[0].overrides = {"prior.type=dataset", "sampler.mode=area", "sampler.edge_supports=true"};
  const auto rows = Evaluator(c).run();
  REQUIRE_FALSE(rows.empty());
  for (const auto& r : rows)
    if (r.bin == "all") CHECK(r.decoded == 700);
}

TEST_CASE("eval: a support-budget sweep with pruning scores every budget and writes the chart and tables", "[eval]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_sweep", 16);
  const std::string ck = test::temp_dir("eval_sweep_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("eval_sweep_run"), 1)).save(ck);
  EvalConfig c;
  c.datasets = {test::tiny_courtyard_set(g)};
  c.methods = {named_method("tiny", "model", ck, {"prior.type=dataset"}),
               named_method("tiny+prune", "model", ck, {"prior.type=dataset"})};
  c.methods[0].budgets = {"px:0.25", "n:900", "detail:1"};
  c.methods[1].budgets = {"n:900"};
  c.methods.push_back(named_method("lift", "lift"));
  c.methods.back().sweep_key = "perturb.depth_scale";
  c.methods.back().sweep_values = {0.8, 1.0};
  c.methods[1].prune.enabled = true;
  c.methods[1].prune.min_contribution = 0.02;
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("eval_sweep_out");
  c.scoring.weights_dir = test::project_weights_dir();
  c.scoring.lpips = {"squeeze"};
  c.scoring.examples = 0;
  c.scoring.gallery = 1;
  c.scoring.reference = "tiny@n900";
  const auto rows = Evaluator(c).run();
  std::map<std::string, ReportRow> all;
  for (const auto& r : rows)
    if (r.bin == "all") all[r.method.label()] = r;
  REQUIRE(all.size() == 6);
  const ReportRow &px = all.at("tiny@px0.25"), &n = all.at("tiny@n900"), &pruned = all.at("tiny+prune@n900");
  REQUIRE(n.pairs > 0);
  CHECK(n.decoded == 900);
  CHECK(n.gaussians == 900);
  CHECK(pruned.decoded == 900);
  CHECK(pruned.gaussians < 900);  // an untrained model leaves faint and hidden base Gaussians
  CHECK(pruned.stage_ms.count("prune") == 1);
  {  // each pair's log line says what pruning removed, and nothing else went
    std::ifstream log(c.scoring.out + "/courtyard/results_tiny_prune_n900.jsonl");
    std::string line;
    REQUIRE(std::getline(log, line));
    const PairResult r = result_from_json(nlohmann::json::parse(line));
    REQUIRE(r.prune_counts.size() == 8);
    CHECK(r.prune_counts.at("low_opacity") + r.prune_counts.at("low_contribution") == r.decoded - r.gaussians);
    CHECK(r.prune_counts.at("merged_members") == 0);
    nlohmann::json bad = result_json(r);
    bad["prune"]["alone"] = -1;
    CHECK_THROWS_WITH(result_from_json(bad), Catch::Contains("prune.alone"));
  }
  CHECK(px.decoded > 0);
  CHECK(all.at("tiny@detail1").decoded > 0);
  for (const char* stage : {"prior", "sampler", "encoder", "decoder", "composer"}) CHECK(n.stage_ms.count(stage) == 1);
  CHECK(std::isfinite(n.peak_mb));
  CHECK(n.peak_mb > 10);
  // Working memory: what a prediction and its render needed, more for more supports, and 0 < work < the peak.
  const ReportRow& detail = all.at("tiny@detail1");
  INFO("work MB: px0.25 " << px.work_mb << " (" << px.decoded << "), n900 " << n.work_mb << ", detail1 "
                          << detail.work_mb << " (" << detail.decoded << ")");
  CHECK(n.work_mb > 0);
  CHECK(n.work_mb < n.peak_mb);
  CHECK(all.at("lift~depth_scale1").work_mb > 0);
  REQUIRE(detail.decoded > 2 * n.decoded);
  CHECK(detail.work_mb > n.work_mb);
  CHECK_THAT(test::read_bytes(c.scoring.out + "/report.csv"), Catch::Contains("work_mb"));
  CHECK(fs::exists(fs::path(c.scoring.out) / "speed_quality.png"));
  const std::string md = test::read_bytes(c.scoring.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("Where the time goes"));
  CHECK_THAT(md, Catch::Contains("| tiny+prune@n900 | 900 -> "));
  {  // the pruning table: what each rule removed, as the mean per pair, adding up to decoded - rendered
    REQUIRE(pruned.prune_counts.count("low_contribution") == 1);
    const double removed = pruned.prune_counts.at("low_opacity") + pruned.prune_counts.at("low_contribution");
    CHECK(removed == Approx(pruned.decoded - pruned.gaussians));
    CHECK(n.prune_counts.empty());  // a method that does not prune has no row
    std::ostringstream row;         // whole numbers as the report prints them (iostream rounding)
    row << std::fixed << std::setprecision(0) << "| tiny+prune@n900 | 900 | " << pruned.prune_counts.at("low_opacity")
        << " | " << pruned.prune_counts.at("low_contribution") << " | 0 | " << pruned.gaussians << " |";
    CHECK_THAT(md, Catch::Contains("Pruning (mean Gaussians per pair") && Catch::Contains(row.str()));
    CHECK_THAT(md, !Catch::Contains("| tiny@n900 | 900 | 0 |"));
    CHECK_THAT(test::read_bytes(c.scoring.out + "/report.json"), Catch::Contains("\"prune_low_contribution\""));
  }
  const std::string csv = test::read_bytes(c.scoring.out + "/report.csv");
  CHECK_THAT(csv, Catch::Contains("decoder_ms"));
  {  // Sweep points are typed fields, never suffixes of a name: in every log record, and as report columns.
    std::ifstream log(c.scoring.out + "/courtyard/results_tiny_px0_25.jsonl");
    std::string line;
    REQUIRE(std::getline(log, line));
    const auto record = nlohmann::json::parse(line);
    CHECK(record["method"] == "tiny");
    CHECK(record["budget"] == "px");
    CHECK(record["sweep_value"].get<double>() == 0.25);
    CHECK_THAT(csv, Catch::StartsWith("dataset,method,sweep_key,budget,sweep_value,bin,"));
    CHECK_THAT(csv, Catch::Contains("\ncourtyard,tiny,,px,0.25,all,") &&
                        Catch::Contains("\ncourtyard,lift,perturb.depth_scale,,0.8,all,"));
    bool typed = false;
    for (const auto& r : nlohmann::json::parse(test::read_bytes(c.scoring.out + "/report.json")))
      typed = typed || (r["method"] == "tiny" && r["budget"] == "n" && r["sweep_value"] == 900 && r["bin"] == "all");
    CHECK(typed);
    // The evaluation's config.json records each method's point, so it names the same methods and files again.
    const auto recorded = config_from_json<EvalConfig>(read_json_file(c.scoring.out + "/config.json"), "config.json");
    const auto expanded = expand_sweeps(recorded.methods);
    REQUIRE(expanded.size() == 6);
    CHECK(expanded[0].label() == "tiny@px0.25");
    CHECK(expanded[0].overrides == expand_sweeps(c.methods)[0].overrides);
    CHECK(expanded.back().label() == "lift~depth_scale1");
  }
  CHECK_THAT(csv, Catch::Contains("peak_mb"));
  // Every method against the reference on the same pairs.
  CHECK_THAT(md, Catch::Contains("## Differences to the reference"));
  const std::string diffs = test::read_bytes(c.scoring.out + "/differences.csv");
  CHECK_THAT(diffs, Catch::Contains("tiny+prune,,n,900,all,tiny@n900"));
  CHECK_THAT(diffs, Catch::Contains("tiny,,px,0.25,all,tiny@n900"));
  // Stability measures on every rendering method, and the perturbation sweep's chart.
  CHECK(n.hole_rate >= 0);
  CHECK(n.hole_rate <= 1);
  CHECK(std::isfinite(n.crack_rate));
  CHECK(std::isfinite(n.normal_deg));
  CHECK(all.at("lift~depth_scale0.8").psnr < all.at("lift~depth_scale1").psnr);  // a wrong scale costs quality
  {  // ... on the same pairs and masks: a perturbation never changes what is scored
    const std::string dir = c.scoring.out + "/courtyard/";
    const ResultsLog scaled(dir + "results_lift_depth_scale0_8.jsonl"), plain(dir + "results_lift_depth_scale1.jsonl");
    REQUIRE(scaled.done().size() == plain.done().size());
    REQUIRE_FALSE(plain.done().empty());
    for (const auto& [i, r] : plain.done()) {
      CHECK(scaled.done().at(i).mask_fraction == r.mask_fraction);
      CHECK(std::isfinite(r.hole_rate));  // the stability fields survive the log's round trip
      CHECK_FALSE(r.motion.empty());
    }
  }
  // Changing a method's options under the same name is refused instead of resuming stale results.
  {
    EvalConfig changed = c;
    changed.methods.back().sweep_values = {0.8};
    changed.methods.back().perturb.exposure = 1.5;
    CHECK_THROWS_WITH(Evaluator(changed).run(), Catch::Contains("was scored with other options"));
    // ... and so is another crack definition: scores with and without an edge margin never mix.
    EvalConfig margin = c;
    margin.scoring.crack_edge_margin = 2;
    CHECK_THROWS_WITH(Evaluator(margin).run(), Catch::Contains("scoring.crack_edge_margin"));
    EvalConfig holes = c;
    holes.scoring.crack_holes = true;
    CHECK_THROWS_WITH(Evaluator(holes).run(), Catch::Contains("scoring.crack_holes"));
    EvalConfig side = c;
    side.scoring.crack_side = "nearer";
    CHECK_THROWS_WITH(Evaluator(side).run(), Catch::Contains("scoring.crack_side"));
    EvalConfig median = c;
    median.scoring.crack_depth = "median";
    CHECK_THROWS_WITH(Evaluator(median).run(), Catch::Contains("scoring.crack_depth"));
  }
  {  // Cracks on the median depth: the same pairs, every crack rate measured, some read otherwise than the mean's.
    EvalConfig median = c;
    median.methods = {named_method("lift", "lift")};
    median.scoring.reference.clear();
    median.scoring.gallery = 1;  // the crack map follows the median depth too
    median.scoring.crack_depth = "median";
    median.scoring.out = test::temp_dir("eval_sweep_median");
    Evaluator(median).run();
    const ResultsLog on_median(median.scoring.out + "/courtyard/results_lift.jsonl"),
        on_mean(c.scoring.out + "/courtyard/results_lift_depth_scale1.jsonl");
    REQUIRE(on_median.done().size() == on_mean.done().size());
    int64_t differ = 0;
    for (const auto& [i, r] : on_mean.done()) {
      const PairResult& m = on_median.done().at(i);
      CHECK(m.mask_fraction == r.mask_fraction);
      CHECK(m.hole_rate == r.hole_rate);  // the same render
      CHECK(std::isfinite(m.crack_rate) == std::isfinite(r.crack_rate));
      differ += std::isfinite(r.crack_rate) && m.crack_rate != r.crack_rate;
    }
    CHECK(differ > 0);
    CHECK_THAT(test::read_bytes(median.scoring.out + "/report.md"), Catch::Contains("scoring.crack_depth = median"));
    int64_t crack_panels = 0;
    for (const auto& e : fs::directory_iterator(median.scoring.out + "/courtyard/gallery"))
      crack_panels += e.path().filename().string().rfind("lift_worst_cracks1_pair", 0) == 0;
    CHECK(crack_panels == 1);
  }
  CHECK(fs::exists(fs::path(c.scoring.out) / "stability.png"));
  CHECK_THAT(md, Catch::Contains("| lift~depth_scale0.8 |"));
  CHECK_THAT(md, Catch::Contains("| lift depth_scale | 0.8, 1 | "));  // the sweep's slope row
  // The finer baseline and motion breakdown, its chart, and the failure gallery (worst by PSNR and holes).
  CHECK_THAT(md, Catch::Contains("| tiny@n900 | baseline [0,0.5) |"));
  CHECK_THAT(md, Catch::Contains("| tiny@n900 | motion "));
  CHECK(fs::exists(fs::path(c.scoring.out) / "baseline.png"));
  CHECK_THAT(test::read_bytes(c.scoring.out + "/breakdown.csv"), Catch::Contains("tiny,,n,900,\"baseline [0,0.5)\""));
  int64_t gallery_psnr = 0, gallery_holes = 0, gallery_cracks = 0;
  fs::path crack_panel;
  for (const auto& e : fs::recursive_directory_iterator(c.scoring.out)) {
    const std::string f = e.path().filename().string();
    if (f.rfind("tiny_n900_worst_psnr1_pair", 0) == 0) ++gallery_psnr;
    if (f.rfind("tiny_n900_worst_holes1_pair", 0) == 0) ++gallery_holes;
    if (f.rfind("tiny_n900_worst_cracks1_pair", 0) == 0) ++gallery_cracks, crack_panel = e.path();
  }
  CHECK(gallery_psnr == 1);
  CHECK(gallery_holes == 1);
  // The worst pair by cracks is the one with the largest crack rate, and its panel has the crack map as a 7th tile.
  const ResultsLog scored(c.scoring.out + "/courtyard/results_tiny_n900.jsonl");
  int64_t most_cracked = -1;
  double most = 0;
  for (const auto& [i, r] : scored.done())
    if (std::isfinite(r.crack_rate) && r.crack_rate > most) most = r.crack_rate, most_cracked = i;
  REQUIRE(most_cracked >= 0);
  REQUIRE(gallery_cracks == 1);
  CHECK_THAT(crack_panel.filename().string(), Catch::EndsWith(cat("_pair", most_cracked, ".png")));
  const cv::Mat crack_png = cv::imread(crack_panel.string());
  REQUIRE_FALSE(crack_png.empty());
  const int tile = crack_png.cols / 7;  // seven frames side by side (the panel writer scales small frames up)
  REQUIRE(crack_png.cols == 7 * tile);
  CHECK(tile * g.eval_height == crack_png.rows * g.eval_width);
  int64_t grey = 0, broken = 0;  // in the last tile: the scored pixels, and the deviant ones (red or blue, BGR)
  for (int y = 0; y < crack_png.rows; ++y)
    for (int x = 6 * tile; x < 7 * tile; ++x) {
      const cv::Vec3b px = crack_png.at<cv::Vec3b>(y, x);
      grey += px[0] == px[1] && px[1] == px[2] && px[0] > 50 && px[0] < 100;
      broken += (px[2] > 200 && px[0] < 100) || (px[0] > 200 && px[2] < 100);
    }
  INFO("scored " << grey << " of " << tile * crack_png.rows << " pixels in the crack tile");
  CHECK(grey > tile * crack_png.rows / 10);  // a tenth of the frame at least is scored (grey)
  CHECK(broken > 0);
  // A log written before the method fields resumes as its file's method (the file name is generated from the
  // same fields, never read back).
  const std::string scaled_log = c.scoring.out + "/courtyard/results_lift_depth_scale0_8.jsonl";
  std::string without_fields;
  for (const auto& j : read_jsonl(scaled_log)) {
    nlohmann::json old = j;
    for (const char* k : {"method", "sweep_key", "sweep_value"}) old.erase(k);
    without_fields += old.dump() + "\n";
  }
  write_file_atomic(scaled_log, without_fields);
  // The per-pair log keeps the new fields, so a resumed run reports the same timings.
  const auto again = Evaluator(c).run();
  CHECK(test::read_bytes(scaled_log) == without_fields);  // nothing scored again
  for (const auto& r : again)
    if (r.method.label() == "lift~depth_scale0.8" && r.bin == "all")
      CHECK(r.psnr == all.at("lift~depth_scale0.8").psnr);
  for (const auto& r : again)
    if (r.method.label() == "tiny@n900" && r.bin == "all") CHECK(r.stage_ms.at("decoder") == n.stage_ms.at("decoder"));
}

TEST_CASE("eval: a COLMAP capture without depth draws pairs from its points3D and scores on full frames",
          "[eval][pairs]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("eval_nodepth", 16);
  const std::string ck = test::temp_dir("eval_nodepth_ck") + "/tiny.safetensors";
  Trainer(test::tiny_train_config(g, test::temp_dir("eval_nodepth_run"), 1)).save(ck);
  EvalDatasetOptions ds = test::tiny_courtyard_set(g);
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
  const Manifest truth = draw_manifest("courtyard", load_eval_dataset(test::tiny_courtyard_set(g)), o);
  CHECK(std::abs(static_cast<double>(m.bin_candidates[0]) - truth.bin_candidates[0]) <=
        0.25 * truth.bin_candidates[0] + 2);

  EvalConfig c;
  c.datasets = {ds};
  c.methods.push_back(
      named_method("lidar", "model", ck, {"variant=lidar", "prior.type=sparse", "prior.sparse.mono=none"}));
  c.protocol = o;
  c.scoring.out = test::temp_dir("eval_nodepth_out");
  c.scoring.lpips = {};
  const auto rows = Evaluator(c).run();
  std::set<std::string> methods;
  for (const auto& r : rows) methods.insert(r.method.label());
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
  auto g = test::eval_dataset_options(test::temp_dir("pairs_ns_nodepth"), 16, {"atrium_nerfstudio"});
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

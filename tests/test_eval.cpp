// Evaluation: pair selection (bins, caps, overlap and rotation filters, determinism, byte-identical
// manifests) and a tiny end-to-end run of two methods with reports and resume.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "core/log.h"
#include "eval/evaluator.h"
#include "eval/pairs.h"
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
  const Manifest m = select_pairs("courtyard", seqs, o);
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
  const Manifest s = select_pairs("courtyard", seqs, strict);
  CHECK(s.bin_candidates[0] < m.bin_candidates[0]);
  // Same seed: byte-identical manifest; another seed: another draw.
  const auto dir = test::temp_dir("pairs_manifest");
  write_manifest(dir + "/a.json", m);
  write_manifest(dir + "/b.json", select_pairs("courtyard", seqs, o));
  CHECK(test::read_bytes(dir + "/a.json") == test::read_bytes(dir + "/b.json"));
  ProtocolOptions other = o;
  other.seed = 6;
  write_manifest(dir + "/c.json", select_pairs("courtyard", seqs, other));
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
  const Manifest m = select_pairs("courtyard", load_eval_dataset(colmap_set(g)), ProtocolOptions{});
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
  c.scoring.weights_dir = test::shared_weights_dir();
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
  if (!test::shared_weights_dir().empty()) CHECK(std::isfinite(lift.lpips.at("squeeze")));
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

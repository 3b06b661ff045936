// Experiment runner: the paired bootstrap against hand-computed cases, and a tiny two-row table trained,
// scored and reported end to end (then resumed without retraining).
#include <catch2/catch.hpp>

#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include "core/config.h"
#include "eval/eval_config.h"
#include "experiment/experiment.h"
#include "io/atomic_file.h"
#include "metrics/stats.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("stats: paired bootstrap matches hand-computed cases", "[experiment][stats]") {
  // Constant differences: the interval collapses onto them.
  const Interval c = paired_bootstrap({3, 4, 5, 6}, {2, 3, 4, 5}, 500);
  CHECK(c.mean == Approx(1.0));
  CHECK(c.lo == Approx(1.0));
  CHECK(c.hi == Approx(1.0));
  CHECK(c.n == 4);
  CHECK(c.excludes_zero());
  // d = {0, 0, 3}: resampled means take 0 with probability (2/3)^3 = 0.296 and 3 with 1/27 = 0.037, both
  // above 2.5%, so the 95% interval is [0, 3] exactly; the mean is 1.
  const Interval t = paired_bootstrap({0, 0, 3}, {0, 0, 0}, 20000, 0.95, 7);
  CHECK(t.mean == Approx(1.0));
  CHECK(t.lo == Approx(0.0));
  CHECK(t.hi == Approx(3.0));
  CHECK_FALSE(t.excludes_zero());
  // d = {0, 2}: resampled means 0, 1, 2 with probabilities 1/4, 1/2, 1/4, so the 30th and 70th
  // percentiles (a 40% interval) both fall in the middle mass: [1, 1].
  const Interval h = paired_bootstrap({0, 2}, {0, 0}, 40000, 0.4, 3);
  CHECK(h.lo == Approx(1.0));
  CHECK(h.hi == Approx(1.0));
  // Non-finite values drop their pair; unequal lengths are an error.
  const Interval f = paired_bootstrap({1, NAN, 2}, {0, 0, INFINITY}, 100);
  CHECK(f.n == 1);
  CHECK(f.mean == Approx(1.0));
  CHECK_THROWS(paired_bootstrap({1, 2}, {1}, 100));
}

TEST_CASE("stats: seed-aware paired bootstrap resamples seeds as well as pairs", "[experiment][stats]") {
  // Every pair of every seed differs by 1: the interval collapses onto it.
  const Interval c = seed_paired_bootstrap({{3, 4}, {5, 6}}, {{2, 3}, {4, 5}}, 500);
  CHECK(c.mean == Approx(1.0));
  CHECK(c.lo == Approx(1.0));
  CHECK(c.hi == Approx(1.0));
  CHECK(c.n == 2);
  // Seed 0 differs by 0 on every pair, seed 1 by 2: the pairs add no spread, and a resample of the two seeds
  // averages 0, 1 or 2 with probabilities 1/4, 1/2, 1/4. So the 95% interval is [0, 2] (a pair-only interval of
  // the seed-averaged differences would be [1, 1]) and the 40% interval is [1, 1].
  const std::vector<std::vector<double>> a = {{0, 0, 0}, {2, 2, 2}}, zero = {{0, 0, 0}, {0, 0, 0}};
  const Interval s = seed_paired_bootstrap(a, zero, 20000, 0.95, 5);
  CHECK(s.mean == Approx(1.0));
  CHECK(s.lo == Approx(0.0));
  CHECK(s.hi == Approx(2.0));
  CHECK_FALSE(s.excludes_zero());
  const Interval narrow = seed_paired_bootstrap(a, zero, 40000, 0.4, 3);
  CHECK(narrow.lo == Approx(1.0));
  CHECK(narrow.hi == Approx(1.0));
  // Seeds are drawn together, seed k of a against seed k of b: here every matched difference is 1, so the interval
  // is [1, 1]; drawing the two methods' seeds apart would spread it over [-3, 5].
  const Interval m = seed_paired_bootstrap({{1, 1, 1}, {5, 5, 5}}, {{0, 0, 0}, {4, 4, 4}}, 2000, 0.95, 9);
  CHECK(m.lo == Approx(1.0));
  CHECK(m.hi == Approx(1.0));
  // One seed is statistically a plain paired bootstrap: d = {0, 0, 3} gives [0, 3] (see the case above).
  const Interval one = seed_paired_bootstrap({{0, 0, 3}}, {{0, 0, 0}}, 20000, 0.95, 7);
  CHECK(one.lo == Approx(0.0));
  CHECK(one.hi == Approx(3.0));
  // A pair with a non-finite value in any seed of either method is dropped from every seed.
  const Interval f = seed_paired_bootstrap({{1, 5, 1}, {1, 1, 1}}, {{0, 0, 0}, {0, NAN, 0}}, 100);
  CHECK(f.n == 2);
  CHECK(f.mean == Approx(1.0));
  // Seeds must match in number, and each seed must hold every pair.
  CHECK_THROWS_WITH(seed_paired_bootstrap({{1}, {2}}, {{1}}, 100), Catch::Contains("2 and 1 seeds"));
  CHECK_THROWS_WITH(seed_paired_bootstrap({{1, 2}, {2}}, {{1, 2}, {2, 3}}, 100), Catch::Contains("seed 1 has 1"));
  CHECK_THROWS(seed_paired_bootstrap({}, {}, 100));
}

TEST_CASE("experiment: two rows trained, scored and reported end to end, then resumed", "[experiment]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("experiment_data", 16);
  const std::string dir = test::temp_dir("experiment");
  // The recipe and the evaluation as files, as users write them.
  TrainConfig recipe = test::tiny_train_config(g, dir + "/unused", 3);
  recipe.train.val_every = 3;
  recipe.data.val_tuples = 1;
  write_file_atomic(dir + "/recipe.json", config_to_json(recipe).dump(2));
  EvalConfig ev;
  EvalDatasetOptions ds;
  ds.name = "courtyard";
  ds.format = "colmap";
  ds.root = generated_eval_root(g.out, "courtyard_colmap");
  ev.datasets = {ds};
  ev.protocol.pairs_per_bin = 2;
  ev.scoring.lpips = {"squeeze"};
  ev.scoring.weights_dir = test::project_weights_dir();
  ev.scoring.examples = 0;
  write_file_atomic(dir + "/eval.json", config_to_json(ev).dump(2));

  ExperimentConfig c;
  c.out = dir + "/out";
  c.train_config = dir + "/recipe.json";
  c.eval_config = dir + "/eval.json";
  c.bootstrap = 200;
  ExperimentRow full;
  full.name = "full";
  full.seeds = {0, 1};
  ExperimentRow pixel;
  pixel.name = "pixel_supports";
  pixel.label = "w/o geometry-guided sampling";
  pixel.train_set = {"model.sampler.mode=pixel"};
  ExperimentRow base;
  base.name = "base_gaussians";
  base.from = "full";
  base.checkpoint = "init";
  base.seeds = {0, 1};  // the reference's two runs at initialisation: a row over two seeds that costs no training
  c.rows = {full, pixel, base};
  // A variant whose prior weights do not exist yet is skipped, not fatal.
  c.variants = {{"depth", {}, {}},
                {"rgb_later", {"prior.type=learned", "prior.learned_weights=" + dir + "/none.st"}, {}}};
  c.baselines = {"lift"};
  Experiment e(c);
  REQUIRE(e.train());
  for (const auto& r : c.rows)
    for (const auto& run : e.runs(r)) CHECK(e.finished(run));
  e.evaluate();
  e.report();
  for (const char* f : {"report.md", "report.csv", "report.json", "curves.png", "deltas.png"})
    CHECK(fs::exists(fs::path(c.out) / f));
  const std::string md = test::read_bytes(c.out + "/report.md");
  CHECK_THAT(md, Catch::Contains("| pixel_supports@depth (w/o geometry-guided sampling) |"));
  CHECK_THAT(md, Catch::Contains("| base_gaussians-s1@depth"));
  CHECK_THAT(md, Catch::Contains("full seed spread"));
  CHECK_THAT(md, !Catch::Contains("@rgb_later"));
  CHECK_THAT(md, Catch::Contains("| full_s1 | 3 |"));
  const auto js = nlohmann::json::parse(test::read_bytes(c.out + "/report.json"));
  bool has_delta = false;
  for (const auto& r : js)
    if (r["row"] == "pixel_supports@depth" && r["bin"] == "all") has_delta = r["delta_psnr"].is_number();
  CHECK(has_delta);
  // Holes and cracks beside PSNR, with paired differences, overall and per bin.
  CHECK_THAT(md, Catch::Contains("Stability (holes"));
  bool has_holes = false;
  for (const auto& r : js)
    if (r["row"] == "pixel_supports@depth" && r["bin"] == "all")
      has_holes = r["holes_pct"].is_number() && r["delta_holes"].is_number();
  CHECK(has_holes);
  // A row with two seeds shared with the reference also gets a seed-aware row. Every pair is finite here, so
  // its mean difference is the mean of its runs' differences to the reference's seed average.
  CHECK_THAT(md, Catch::Contains("Rows over their training seeds"));
  CHECK_THAT(md, Catch::Contains("| base_gaussians@depth seeds 0+1 |"));
  CHECK_THAT(md, !Catch::Contains("pixel_supports@depth seeds"));  // one seed: no such row
  std::map<std::string, nlohmann::json> all_bins;
  for (const auto& r : js)
    if (r["bin"] == "all" && r["variant"] == "depth") all_bins[r["row"].get<std::string>()] = r;
  REQUIRE(all_bins.count("base_gaussians@depth seeds 0+1"));
  const auto& over = all_bins["base_gaussians@depth seeds 0+1"];
  CHECK(over["interval"] == "seeds and pairs");
  const std::string csv = test::read_bytes(c.out + "/report.csv");
  CHECK_THAT(csv, Catch::Contains(",delta_cracks_hi,interval\n"));
  CHECK_THAT(csv, Catch::Contains(",base_gaussians@depth seeds 0+1,all,"));
  CHECK_THAT(csv, Catch::Contains(",seeds and pairs\n") && Catch::Contains(",pairs\n"));
  CHECK(all_bins["base_gaussians-s0@depth"]["interval"] == "pairs");
  const double runs_mean = (all_bins["base_gaussians-s0@depth"]["delta_psnr"].get<double>() +
                            all_bins["base_gaussians-s1@depth"]["delta_psnr"].get<double>()) /
                           2;
  CHECK(over["delta_psnr"].get<double>() == Approx(runs_mean).margin(1e-9));
  CHECK(over["delta_psnr_lo"].get<double>() <= over["delta_psnr"].get<double>());
  CHECK(over["delta_psnr_hi"].get<double>() >= over["delta_psnr"].get<double>());
  CHECK(over["psnr"].get<double>() == Approx((all_bins["base_gaussians-s0@depth"]["psnr"].get<double>() +
                                              all_bins["base_gaussians-s1@depth"]["psnr"].get<double>()) /
                                             2));
  // Beside it, each seed against its own reference seed: ΔPSNR over all pairs, then holes and cracks at the last bin.
  CHECK_THAT(md, Catch::Contains("| per seed: ΔPSNR / "));
  for (int seed : {0, 1}) {
    const double d = all_bins[cat("base_gaussians-s", seed, "@depth")]["psnr"].get<double>() -
                     all_bins[cat("full-s", seed, "@depth")]["psnr"].get<double>();
    std::ostringstream want;
    want << (seed ? "; s1 " : " | s0 ") << (d >= 0 ? "+" : "") << std::fixed << std::setprecision(2) << d << " / ";
    CHECK_THAT(md, Catch::Contains(want.str()));
  }
  // Resume: nothing is retrained (the run's log does not grow).
  const std::string log = test::read_bytes(c.out + "/runs/full_s0/train_log.jsonl");
  Experiment again(c);
  REQUIRE(again.train());
  CHECK(test::read_bytes(c.out + "/runs/full_s0/train_log.jsonl") == log);
  // A run trained under another recipe is never reused silently: training and scoring name the key.
  ExperimentConfig changed = c;
  changed.train_set = {"loss.smooth=0.2"};
  const ExperimentRun pixel_run = again.runs(c.rows[1]).at(0);
  CHECK(again.config_drift(pixel_run).empty());
  CHECK_THAT(Experiment(changed).config_drift(pixel_run), Catch::Contains("loss.smooth = 0.1"));
  CHECK_THROWS_WITH(Experiment(changed).train({"pixel_supports"}),
                    Catch::Contains("was trained with another configuration") && Catch::Contains("loss.smooth"));
  CHECK_THROWS_WITH(Experiment(changed).evaluate({"pixel_supports"}), Catch::Contains("loss.smooth"));
  // A longer recipe is no drift: the run resumes to the new step count instead of being skipped.
  ExperimentConfig longer = c;
  longer.train_set = {"train.steps=4"};
  Experiment more(longer);
  CHECK(more.config_drift(pixel_run).empty());
  CHECK_FALSE(more.finished(pixel_run));
  REQUIRE(more.train({"pixel_supports"}));
  CHECK(more.finished(pixel_run));
  CHECK_THROWS_WITH(again.evaluate({}, {"nope"}), Catch::Contains("no variant 'nope'"));
  // A misspelt row or a seed no selected row lists fails before anything runs, instead of doing nothing.
  CHECK_THROWS_WITH(again.train({"ful"}), Catch::Contains("no row 'ful'"));
  CHECK_THROWS_WITH(again.evaluate({"ful"}), Catch::Contains("no row 'ful'"));
  CHECK_THROWS_WITH(again.train({"pixel_supports"}, {1}), Catch::Contains("--seeds selects no run"));
  CHECK(again.train({"full", "pixel_supports"}, {1}));  // full lists seed 1 (already trained: skipped)
  CHECK(again.train({"base_gaussians"}, {1}));          // reuses full's runs: nothing to train, and no error
  // A row reusing an unknown row is a clear error.
  ExperimentConfig bad = c;
  bad.rows[2].from = "nope";
  CHECK_THROWS_WITH(Experiment(bad), Catch::Contains("reuses unknown row 'nope'"));
}

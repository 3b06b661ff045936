// Scale-out: 2 data-parallel ranks (separate processes on loopback, c10d/Gloo) equal 1 rank with the
// doubled batch, resume exactly, and fail clearly; 3 evaluation shards merge into the unsharded reports.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "core/config.h"
#include "eval/evaluator.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/csv.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/data_parallel.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
const std::string kTrain = (fs::path(ISPLAT_BINARY_DIR) / "infinisplat-train").string();

int free_port() {
  static std::mt19937 rng(static_cast<unsigned>(std::chrono::steady_clock::now().time_since_epoch().count()));
  return 20000 + static_cast<int>(rng() % 20000);
}

// Runs `ranks` processes of infinisplat-train on `config` with `sets`; returns the shell's exit status.
int train_ranks(int ranks, const std::string& config, const std::string& sets, const std::string& log) {
  if (ranks == 1)
    return std::system(cat(kTrain, " --config ", config, " --threads 1 ", sets, " > ", log, " 2>&1").c_str());
  const int port = free_port();
  std::string cmd = "sh -c '";
  for (int r = 0; r < ranks; ++r)
    cmd += cat("RANK=", r, " WORLD_SIZE=", ranks, " MASTER_ADDR=127.0.0.1 MASTER_PORT=", port, " ", kTrain,
               " --config ", config, " --threads 1 ", sets, " > ", log, ".", r, " 2>&1 & p", r, "=$!; ");
  cmd += "s=0; ";
  for (int r = 0; r < ranks; ++r) cmd += cat("wait $p", r, " || s=1; ");
  cmd += "exit $s'";
  return std::system(cmd.c_str());
}

std::map<std::string, torch::Tensor> model_of(const std::string& run) {
  std::map<std::string, torch::Tensor> out;
  for (const auto& [k, v] : load_checkpoint(run + "/checkpoints/last.safetensors").tensors)
    if (k.rfind("model/", 0) == 0) out[k] = v;
  return out;
}

double max_relative_difference(const std::map<std::string, torch::Tensor>& a,
                               const std::map<std::string, torch::Tensor>& b) {
  REQUIRE(a.size() == b.size());
  double worst = 0;
  for (const auto& [k, t] : a) {
    const auto& u = b.at(k);
    if (!t.is_floating_point()) continue;
    const double scale = std::max(1e-3, t.abs().max().item<double>());
    worst = std::max(worst, (t - u).abs().max().item<double>() / scale);
  }
  return worst;
}
}  // namespace

TEST_CASE("dist: 2 ranks x batch 1 equal 1 rank x batch 2, and a resumed 2-rank run continues exactly", "[dist]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("dist_data", 8);
  const std::string dir = test::temp_dir("dist");
  TrainConfig c = test::tiny_train_config(data, dir + "/unused", 3);
  c.train.checkpoint_every = 3;
  write_file_atomic(dir + "/tiny.json", config_to_json(c).dump(2));
  const std::string cfg = dir + "/tiny.json";
  REQUIRE(train_ranks(1, cfg, cat("--set data.batch_size=2 --set train.out=", dir, "/one"), dir + "/one.log") == 0);
  REQUIRE(train_ranks(2, cfg, cat("--set data.batch_size=1 --set train.out=", dir, "/two"), dir + "/two.log") == 0);
  const auto one = model_of(dir + "/one"), two = model_of(dir + "/two");
  const double diff = max_relative_difference(one, two);
  INFO("max relative weight difference " << diff);
  CHECK(diff < 1e-5);
  // Only rank 0 wrote: one log, one config; the training actually moved the weights.
  CHECK(test::read_bytes(dir + "/two/train_log.jsonl").find("\"step\":3") != std::string::npos);
  CHECK(max_relative_difference(two, [&] {
          std::map<std::string, torch::Tensor> init;
          for (const auto& [k, v] : load_checkpoint(dir + "/two/checkpoints/init.safetensors").tensors)
            if (k.rfind("model/", 0) == 0) init[k] = v;
          return init;
        }()) > 1e-4);

  // Resume: 5 steps in two sittings (stop at 3, then --resume auto) equal 5 steps straight.
  const std::string five = "--set train.steps=5 --set train.checkpoint_every=5 --set data.batch_size=1";
  REQUIRE(train_ranks(2, cfg, cat(five, " --set train.out=", dir, "/straight"), dir + "/s.log") == 0);
  REQUIRE(train_ranks(2, cfg, cat(five, " --set train.stop_at=3 --set train.out=", dir, "/split"), dir + "/a.log") ==
          0);
  CHECK(load_checkpoint(dir + "/split/checkpoints/last.safetensors").step() == 3);
  REQUIRE(train_ranks(2, cfg, cat(five, " --resume auto --set train.out=", dir, "/split"), dir + "/b.log") == 0);
  CHECK(load_checkpoint(dir + "/split/checkpoints/last.safetensors").step() == 5);
  CHECK(max_relative_difference(model_of(dir + "/straight"), model_of(dir + "/split")) == 0.0);
}

TEST_CASE("dist: a parameter one rank's batch did not reach is averaged with that rank's zero", "[dist]") {
  // A parameter that gets no gradient on one rank (no loss term reached it there): the ranks must still send
  // the same gradient list (else the all-reduce buffers differ in size).
  const int port = free_port();
  std::vector<torch::Tensor> got(2);
  std::vector<std::string> errors(2);
  auto rank = [&](int r) {
    try {
      DistOptions o;
      o.rank = r, o.world_size = 2, o.master_port = port, o.timeout_s = 30;
      DataParallel dp(o);
      auto a = torch::full({3}, 1.0f).requires_grad_(), b = torch::full({2}, 1.0f).requires_grad_();
      auto frozen = torch::ones({2});  // no gradient anywhere: stays without one
      (a * float(r + 1)).sum().backward();
      if (r == 0) (b * 4.0f).sum().backward();
      dp.average_gradients({a, b, frozen});
      got[r] = torch::cat({a.grad(), b.grad()});
      if (frozen.grad().defined()) errors[r] = "the frozen tensor got a gradient";
    } catch (const std::exception& e) {
      errors[r] = e.what();
    }
  };
  std::thread r1(rank, 1);
  rank(0);
  r1.join();
  INFO(errors[0] << " | " << errors[1]);
  REQUIRE(errors[0].empty());
  REQUIRE(errors[1].empty());
  const auto want = torch::tensor({1.5f, 1.5f, 1.5f, 2.0f, 2.0f});  // a: (1 + 2) / 2; b: (4 + 0) / 2
  CHECK(torch::equal(got[0], want));
  CHECK(torch::equal(got[1], want));
}

TEST_CASE("dist: an unreachable store or a mismatched world size fails clearly within the timeout", "[dist]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("dist_bad_data", 8);
  const std::string dir = test::temp_dir("dist_bad");
  TrainConfig c = test::tiny_train_config(data, dir + "/run", 2);
  c.dist.timeout_s = 3;
  write_file_atomic(dir + "/tiny.json", config_to_json(c).dump(2));
  const int port = free_port();
  const auto t0 = std::chrono::steady_clock::now();
  // Rank 1 alone: nobody hosts the store.
  const int rc = std::system(cat("RANK=1 WORLD_SIZE=2 MASTER_ADDR=127.0.0.1 MASTER_PORT=", port, " ", kTrain,
                                 " --config ", dir, "/tiny.json --threads 1 > ", dir, "/lonely.log 2>&1")
                                 .c_str());
  CHECK(rc != 0);
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30));
  const std::string lonely = test::read_bytes(dir + "/lonely.log");
  CHECK_THAT(lonely, Catch::Contains("rank 1") && Catch::Contains(cat("127.0.0.1:", port)));
  // Two ranks that disagree on the world size.
  const int port2 = free_port();
  std::system(cat("sh -c 'RANK=0 WORLD_SIZE=2 MASTER_ADDR=127.0.0.1 MASTER_PORT=", port2, " ", kTrain, " --config ",
                  dir, "/tiny.json --threads 1 > ", dir,
                  "/w0.log 2>&1 & RANK=1 WORLD_SIZE=3 MASTER_ADDR=127.0.0.1 MASTER_PORT=", port2, " ", kTrain,
                  " --config ", dir, "/tiny.json --threads 1 > ", dir, "/w1.log 2>&1; wait'")
                  .c_str());
  const std::string both = test::read_bytes(dir + "/w0.log") + test::read_bytes(dir + "/w1.log");
  CHECK_THAT(both, Catch::Contains("world size"));
  // A rank outside the world is refused before anything starts.
  CHECK(std::system(
            cat("RANK=2 WORLD_SIZE=2 ", kTrain, " --config ", dir, "/tiny.json > ", dir, "/out.log 2>&1").c_str()) !=
        0);
  CHECK_THAT(test::read_bytes(dir + "/out.log"), Catch::Contains("rank 2 is not in [0, world size 2)"));
}

TEST_CASE("eval: 3 shards merged give the unsharded reports (timings aside)", "[dist][eval]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("shard_data", 16);
  EvalConfig c;
  EvalDatasetOptions ds;
  ds.name = "courtyard";
  ds.format = "colmap";
  ds.root = generated_eval_root(g.out, "courtyard_colmap");
  c.datasets = {ds};
  c.protocol.pairs_per_bin = 3;
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  c.scoring.out = test::temp_dir("shard_whole");
  Evaluator(c).run();
  EvalConfig s = c;
  s.scoring.out = test::temp_dir("shard_parts");
  for (int k = 0; k < 3; ++k) {
    Evaluator part(s);
    part.set_shard(k, 3);
    part.run();
    CHECK(fs::exists(s.scoring.out + cat("/courtyard/results_lift.shard-", k, "-of-3.jsonl")));
  }
  CHECK_FALSE(fs::exists(s.scoring.out + "/report.md"));                                  // shards write no report
  CHECK_THROWS_WITH(Evaluator(s).merge(4), Catch::Contains("shard 0/4 has no results"));  // only 3 were run
  EvalConfig other = s;  // merging under another crack definition than the shards were scored with is refused
  other.scoring.crack_edge_margin = 2;
  CHECK_THROWS_WITH(Evaluator(other).merge(3), Catch::Contains("scored with other options"));
  Evaluator(s).merge(3);
  // The reports agree once the timing columns are dropped.
  auto strip = [](const std::string& path) {
    auto j = nlohmann::json::parse(test::read_bytes(path));
    for (auto& r : j) r.erase("infer_ms"), r.erase("render_ms");
    return j.dump();
  };
  CHECK(strip(c.scoring.out + "/report.json") == strip(s.scoring.out + "/report.json"));
  auto csv_without_times = [](const std::string& path) {
    CsvTable t = read_csv(path);
    std::string out;
    for (const auto& row : t.rows)
      for (size_t k = 0; k < row.size(); ++k)
        if (t.header[k] != "infer_ms" && t.header[k] != "render_ms") out += row[k] + ",";
    return out;
  };
  CHECK(csv_without_times(c.scoring.out + "/report.csv") == csv_without_times(s.scoring.out + "/report.csv"));
  CHECK(test::read_bytes(c.scoring.out + "/courtyard/manifest.json") ==
        test::read_bytes(s.scoring.out + "/courtyard/manifest.json"));
}

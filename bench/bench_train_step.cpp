// Benchmark: one training step at the quickstart settings (configs/quickstart.json: ViT-S, the default model,
// 256x192, 1 context + 3 targets), and where its time goes.
// usage: bench_train_step [hypersim_root] [threads] [config] (--help); without a root (or with "") a small scene is
// generated first; config defaults to configs/quickstart.json (e.g. configs/recipe/recipe.json).
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <torch/torch.h>

#include "bench/flops.h"
#include "core/app.h"
#include "core/args.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/precision.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "core/weights.h"
#include "data/synth/generate.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

int time_steps(std::string root, const std::string& config_path, const std::string& precision) {
  const fs::path tmp = fs::temp_directory_path() / "isplat_bench_train";
  if (root.empty()) {
    set_log_level(LogLevel::Warn);
    GenerateOptions g;
    g.out = (tmp / "data").string();
    g.train_scenes = 1, g.val_scenes = 0, g.test_scenes = 0, g.frames = 16, g.supersample = 1, g.eval_scenes = 0;
    generate_datasets(g);
    root = generated_hypersim_root(g.out);
  }
  set_log_level(LogLevel::Warn);
  auto config = load_config<TrainConfig>(
      config_path, {"data.hypersim.root=" + root, "data.workers=0", "model.prior.type=dataset",
                    "train.out=" + (tmp / "run").string(), "train.val_every=100000", "runtime.precision=" + precision});
  use_precision(config.runtime.precision, "bench_train_step: --precision");
  if (find_weights_file(config.loss.perceptual_weights).empty())
    std::fprintf(stderr, "bench_train_step: no perceptual weights, the step is timed without that term (%s)\n",
                 missing_weights_hint().c_str());
  Trainer trainer(config);
  std::map<std::string, std::vector<double>> t;
  std::vector<double> supports;
  const int steps = 6;
  for (int i = 0; i < steps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const StepStats s = trainer.train_step();
    const double total = ms_since(t0);
    if (i == 0) continue;  // warm-up
    t["total"].push_back(total);
    supports.push_back(static_cast<double>(s.supports));
    for (const auto& [k, v] : s.timings_ms) t[k].push_back(v);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("training step of %s (%d threads, %s, %d steps after warm-up), median ms:\n", config_path.c_str(),
              at::get_num_threads(), precision_name(compute_precision()), steps - 1);
  for (const auto& [k, v] : t) std::printf("  %-12s %8.1f\n", k.c_str(), median(v));
  std::printf("(backward includes render_bwd; the decoder and encoder backward make up the rest)\n");
  // Forward and backward of the networks: about 3x the forward's count (the backward computes two products per one).
  const auto& views = config.data.tuples;
  const double n = median(supports) / static_cast<double>(config.data.batch_size);
  const bench::StageFlops f = bench::count_flops(config.model, views.width, views.height, static_cast<int64_t>(n));
  const double gflop = 3.0 * config.data.batch_size * (f.encoder() + f.decoder()) * 1e-9;
  auto stage_ms = [&](const char* stage) { return t.count(stage) ? median(t.at(stage)) : 0.0; };
  const double net_ms = stage_ms("encoder") + stage_ms("decoder") + stage_ms("backward") - stage_ms("render_bwd");
  std::printf(
      "counted: %.1f GFLOP per step in the networks (forward: encoder %.1f, decoder %.1f at %.0f supports per "
      "view; backward about twice that), %.0f GFLOP/s over encoder + decoder + backward - render_bwd\n",
      gflop, f.encoder() * 1e-9, f.decoder() * 1e-9, n, gflop / (net_ms * 1e-3));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_main("bench_train_step", [&] {
    std::string root, threads_text = "0", config_path = std::string(ISPLAT_SOURCE_DIR) + "/configs/quickstart.json";
    ArgParser parser("bench_train_step",
                     "Times training steps (one warm-up, then 5) and where their time goes, on a generated scene "
                     "unless a Hypersim root is given.");
    parser.positional("hypersim_root", root, "Hypersim-format root; empty (\"\") generates a small scene", false);
    parser.positional("threads", threads_text, "threads (0 = all cores)", false);
    parser.positional("config", config_path, "training config (default configs/quickstart.json)", false);
    std::string precision = "fp32";
    parser.option("--precision", precision, "the networks' matmuls: fp32, bf16 (fp32 master weights) or auto",
                  "fp32|bf16|auto");
    if (!parser.parse(argc, argv)) return 0;
    const auto threads = parse_int(threads_text);
    ISPLAT_CHECK(threads && *threads >= 0, "bench_train_step: threads must be a whole number >= 0, got '", threads_text,
                 "'");
    configure_threads(*threads);
    return time_steps(root, config_path, precision);
  });
}

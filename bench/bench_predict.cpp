// Benchmark: one prediction (no autograd) from image + depth to Gaussians, and where its time and memory go: the
// defaults (ViT-S at 256x192: a support per pixel and behind silhouettes, the dense head), the paper's layout at the
// quickstart's size (100k and 40k area supports, the implicit decoder) and, with --paper, the paper's setting (ViT-L,
// 1.5M supports, 1536x1152) and the default model at that size. Untrained weights: the time does not depend on them.
// usage: bench_predict [--paper] [--threads N] [--runs N] (--help)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <torch/torch.h>

#include "bench/flops.h"
#include "core/app.h"
#include "core/args.h"
#include "core/error.h"
#include "core/log.h"
#include "core/precision.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "decoder/feature_sampler.h"
#include "geometry/camera_torch.h"
#include "model/infinisplat.h"
#include "model/model_io.h"

using namespace isplat;
using Clock = std::chrono::steady_clock;

namespace {

// A room-like depth map: a slanted floor-to-wall surface with boxes, plus a textured image.
std::pair<torch::Tensor, torch::Tensor> scene(int64_t W, int64_t H) {
  torch::manual_seed(0);
  auto v = torch::linspace(0, 1, H).view({H, 1}), u = torch::linspace(0, 1, W).view({1, W});
  auto depth = 2.0 + 3.0 * (1.0 - v) + 0.5 * torch::sin(6.0 * u) * torch::cos(4.0 * v);
  auto box = (u > 0.3) & (u < 0.5) & (v > 0.5) & (v < 0.8);
  depth = torch::where(box, depth - 1.0, depth).to(torch::kFloat32).contiguous();
  auto image = torch::clamp(0.5 + 0.2 * torch::randn({3, H, W}), 0.0, 1.0);
  return {depth, image};
}

// The stages' analytic counts, the rates they achieve, and this machine's matmul rates at their dominant shapes.
void print_counts(const ModelOptions& o, int64_t W, int64_t H, int64_t supports, double encoder_ms, double decoder_ms) {
  const bench::StageFlops f = bench::count_flops(o, W, H, supports);
  std::printf(
      "  counted: encoder %.1f GFLOP (ViT linears %.1f, attention %.1f, CNN %.1f) at %.0f GFLOP/s; decoder %.1f "
      "GFLOP (maps %.2f, MLP %.1f) at %.0f GFLOP/s\n",
      f.encoder() * 1e-9, f.vit_linear * 1e-9, f.vit_attention * 1e-9, f.cnn * 1e-9, f.encoder() / (encoder_ms * 1e6),
      f.decoder() * 1e-9, f.decoder_maps * 1e-9, f.decoder_mlp * 1e-9, f.decoder() / (decoder_ms * 1e6));
  const int64_t C = o.encoder.vit.dim(), heads = o.encoder.vit.num_heads();
  const int64_t N = (H / 16) * (W / 16) + 1 + o.encoder.vit.registers;
  const int64_t rows = std::max<int64_t>(1, (o.encoder.vit.attention_chunk_mb << 20) / (heads * N * 4));
  const int64_t chunk = std::min(o.decoder.chunk, supports);
  const bool bf16 = cpu_has_bf16();
  const std::string cap = onednn_bf16_cap();
  auto both = [&](const char* what, const std::function<double(torch::Dtype)>& rate) {
    std::printf("  machine: %-44s fp32 %6.0f GFLOP/s", what, rate(torch::kFloat32));
    if (bf16)
      std::printf(", bf16 %6.0f GFLOP/s\n", rate(torch::kBFloat16));
    else
      std::printf(", bf16 n/a (%s)\n", cap.empty()
                                           ? "no AVX512-BF16 or AMX"
                                           : ("no AVX512-BF16 or AMX, or " + cap + " keeps oneDNN off them").c_str());
  };
  both(cat("ViT MLP linear [", N, " x ", C, "] -> ", 4 * C).c_str(),
       [&](torch::Dtype t) { return bench::linear_gflops(N, C, 4 * C, t); });
  both(cat("attention scores, ", heads, " heads x ", N, "^2 x ", C / heads).c_str(),
       [&](torch::Dtype t) { return bench::attention_gflops(heads, N, C / heads, rows, t); });
  if (o.decoder.mode == "implicit")
    both(cat("decoder MLP linear [", chunk, " x ", C, "] -> ", C).c_str(),
         [&](torch::Dtype t) { return bench::linear_gflops(chunk, C, C, t); });
}

void run(const char* label, const ModelOptions& o, int64_t W, int64_t H, int runs, bool warm_up = true) {
  InfiniSplat model(o);
  model->eval();
  const auto [depth, image] = scene(W, H);
  const auto K = make_K(0.8 * W, 0.8 * W, W / 2.0, H / 2.0);
  const auto valid = torch::ones({H, W});
  std::map<std::string, std::vector<double>> ms;
  double peak = 0;
  int64_t supports = 0;
  for (int r = warm_up ? 0 : 1; r < runs + 1; ++r) {  // run 0 warms up
    reset_peak_memory();
    const auto t0 = Clock::now();
    const Prediction p = model->predict(image, K, torch::eye(4), depth, valid);
    const double total = ms_since(t0);
    if (r == 0) continue;
    supports = p.supports.count();
    peak = std::max(peak, peak_memory_mb());
    for (const auto& [k, v] : p.timings_ms) ms[k].push_back(v);
    ms["total"].push_back(total);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("%-40s %5lldx%-5lld supports %8lld |", label, (long long)W, (long long)H, (long long)supports);
  for (const char* k : {"sampler", "encoder", "decoder", "composer", "total"})
    std::printf(" %s %8.1f", k, median(ms[k]));
  std::printf(" ms | peak %7.0f MB\n", peak);
  print_counts(o, W, H, supports, median(ms["encoder"]), median(ms["decoder"]));
  if (!model->decoder || !warm_up) return;
  // The decoder's parts on the same supports: one plain feature query, the whole decoder, and its MLP alone; the
  // decoder minus the MLP (medians over the runs) is the fused query of both branches with the gate. A per-run
  // difference went negative on a noisy machine (-47 ms, Zen 3, 2026-12-02), so the medians are subtracted instead.
  const auto f = model->encoder->forward(image.unsqueeze(0));
  const auto uv = model->predict(image, K, torch::eye(4), depth, valid).supports.uv;
  std::vector<double> query, mlp, whole;
  for (int r = 0; r < runs; ++r) {
    auto& d = model->decoder;
    auto h = torch::randn({uv.size(0), d->dino_dim > 0 ? d->dino_dim : d->cnn_dim});
    auto t0 = Clock::now();
    auto q = sample_features(f.dino, uv, W, H);
    query.push_back(ms_since(t0));
    t0 = Clock::now();
    auto out = d->mlp_head(h);
    mlp.push_back(ms_since(t0));
    t0 = Clock::now();
    auto delta = d->forward(uv, W, H, f);
    whole.push_back(ms_since(t0));
  }
  int64_t macs = 0;
  for (const auto& p : model->decoder->mlp->parameters())
    if (p.dim() == 2) macs += p.numel();
  macs += model->decoder->head->weight.numel();
  const double fused = median(whole) - median(mlp);
  if (fused < 0) std::printf("  (the MLP's timing noise exceeds the fused query below: rerun with more --runs)\n");
  std::printf(
      "%-40s one %lld-channel query %6.1f ms, fused query and gate %6.1f ms, MLP+head %7.1f ms (%.1f GFLOP/s; matmul "
      "1024^2: %.1f GFLOP/s)\n",
      "  decoder parts", (long long)f.dino.size(1), median(query), fused, median(mlp),
      2.0 * macs * uv.size(0) / (median(mlp) * 1e6), matmul_gflops(1024));
}

}  // namespace

int main(int argc, char** argv) {
  return run_main("bench_predict", [&] {
    bool paper = false;
    int64_t threads = 0, runs = 5;
    std::string precision = "fp32";
    ArgParser parser(
        "bench_predict",
        "Times one prediction (no autograd) from image and depth to Gaussians, stage by stage, with "
        "untrained weights at 256x192 with ViT-S: the defaults, and the paper's layout with 100k and 40k supports.");
    parser.flag("--paper", paper,
                "also the paper's setting (ViT-L, 1.5M supports, 1536x1152) and the default model at its size "
                "(one cold run each)");
    parser.option("--threads", threads, "threads (0 = all cores)");
    parser.option("--runs", runs, "timed runs per setting (after one warm-up)");
    parser.option("--precision", precision, "the encoder's and decoder's matmuls: fp32, bf16 or auto",
                  "fp32|bf16|auto");
    if (!parser.parse(argc, argv)) return 0;
    ISPLAT_CHECK(runs >= 1, "bench_predict: --runs must be at least 1, got ", runs);
    configure_threads(threads);
    use_precision(precision, "bench_predict: --precision");
    set_log_level(LogLevel::Warn);
    torch::NoGradGuard no_grad;
    std::printf("predict benchmark (median of %lld runs after one warm-up), %d threads, %s, BLAS: %s\n",
                (long long)runs, at::get_num_threads(), precision_name(compute_precision()), loaded_blas().c_str());
    ModelOptions o;
    o.encoder.vit.size = "S";
    run("default: ViT-S, pixels+edges, dense head", o, 256, 192, static_cast<int>(runs));
    o.sampler = model_defaults(2).sampler;  // the paper's layout (with the lab's edge supports) at a fixed budget
    o.sampler.budget_mode = "fixed";
    o.sampler.budget = 100000;
    o.decoder.mode = "implicit";
    run("paper's layout: ViT-S, 100k supports", o, 256, 192, static_cast<int>(runs));
    o.sampler.budget = 40000;
    run("ViT-S, 40k supports (0.85 per pixel)", o, 256, 192, static_cast<int>(runs));
    if (paper) {
      o.encoder.vit.size = "L";
      o.sampler.budget = 1500000;
      run("paper: ViT-L, 1.5M supports (one cold run)", o, 1536, 1152, 1, /*warm_up=*/false);
      ModelOptions d;
      d.encoder.vit.size = "L";
      run("the default at the paper's size (cold)", d, 1536, 1152, 1, /*warm_up=*/false);
    }
    return 0;
  });
}

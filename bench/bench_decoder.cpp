// Benchmark: the implicit decoder's forward and backward (the paper's method; the default model decodes with the dense
// head, timed by bench_predict) at training and paper-scale support counts.
#include <chrono>
#include <cstdio>

#include <torch/torch.h>

#include "core/progress.h"
#include "core/runtime.h"
#include "decoder/feature_sampler.h"
#include "decoder/implicit_decoder.h"

using namespace isplat;
using Clock = std::chrono::steady_clock;

namespace {

void run(int64_t dino_dim, int64_t n, int64_t W, int64_t H) {
  DecoderOptions o;
  ImplicitDecoder d(o, dino_dim, 128);
  EncoderFeatures f{torch::randn({1, dino_dim, H / 16, W / 16}, torch::requires_grad()),
                    torch::randn({1, 128, H / 4, W / 4}, torch::requires_grad())};
  auto uv = torch::rand({n, 2}) * torch::tensor({float(W), float(H)});
  std::vector<double> fwd, bwd, sample, grid;
  for (int r = 0; r < 4; ++r) {
    auto t0 = Clock::now();
    auto delta = d->forward(uv, W, H, f);
    fwd.push_back(ms_since(t0));
    t0 = Clock::now();
    delta.sum().backward();
    bwd.push_back(ms_since(t0));
    torch::NoGradGuard g;
    t0 = Clock::now();
    auto q = sample_features(f.dino, uv, W, H);
    sample.push_back(ms_since(t0));
    t0 = Clock::now();
    auto q2 = query_features(f.dino, uv, W, H);
    grid.push_back(ms_since(t0));
  }
  std::sort(fwd.begin(), fwd.end());
  std::sort(bwd.begin(), bwd.end());
  std::sort(sample.begin(), sample.end());
  std::sort(grid.begin(), grid.end());
  std::printf(
      "C_d %4lld  supports %8lld  forward %8.1f ms  backward %8.1f ms  | one %lld-channel query: ours %6.1f ms, "
      "grid_sample %6.1f ms\n",
      (long long)dino_dim, (long long)n, fwd[1], bwd[1], (long long)dino_dim, sample[1], grid[1]);
}
}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory();  // as every executable does (run_main)
  configure_threads(argc > 1 ? std::atoll(argv[1]) : 0);
  std::printf("implicit decoder benchmark, %d threads\n", at::get_num_threads());
  run(384, 100000, 256, 192);  // the paper's layout at the quickstart's size: ViT-S, 100k supports
  run(384, 30000, 256, 192);
  run(1024, 100000, 512, 384);  // ViT-L width
  return 0;
}

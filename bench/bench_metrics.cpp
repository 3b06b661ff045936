// Benchmark: the evaluation and loss hot paths other than the renderer: SSIM, LPIPS-squeeze, the
// grid-hash kNN for smoothness, and the projected mask.
#include <chrono>
#include <cstdio>

#include <torch/torch.h>

#include "core/progress.h"
#include "core/runtime.h"
#include "loss/knn.h"
#include "metrics/mask.h"
#include "metrics/metrics.h"

using namespace isplat;
using Clock = std::chrono::steady_clock;

namespace {
template <class F>
double median_ms(F f, int reps = 5) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    auto t0 = Clock::now();
    f();
    t.push_back(ms_since(t0));
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  configure_threads(argc > 1 ? std::atoll(argv[1]) : 0);
  std::printf("metrics and neighbour-search benchmark, %d threads\n", at::get_num_threads());
  torch::manual_seed(0);
  for (auto [W, H] : std::vector<std::pair<int64_t, int64_t>>{{384, 256}, {1536, 1024}, {2016, 1344}}) {
    auto a = torch::rand({3, H, W}), b = (a + 0.1 * torch::randn_like(a)).clamp(0, 1);
    auto mask = torch::ones({H, W});
    std::printf("SSIM   %4lldx%-4lld  %8.1f ms   PSNR %6.2f ms\n", (long long)W, (long long)H,
                median_ms([&] { ssim(a, b, mask); }), median_ms([&] { psnr(a, b, mask); }));
  }
  std::string why;
  const char* dirs[] = {"../shared/weights", "/work/shared/weights"};
  for (const char* d : dirs) {
    auto lp = Lpips::from_folder("squeeze", d, why);
    if (!lp) continue;
    for (auto [W, H] : std::vector<std::pair<int64_t, int64_t>>{{384, 256}, {1536, 1024}}) {
      auto a = torch::rand({3, H, W}), b = torch::rand({3, H, W});
      std::printf("LPIPS-squeeze %4lldx%-4lld %8.1f ms\n", (long long)W, (long long)H, median_ms([&] { (*lp)(a, b); }));
    }
    break;
  }
  for (int64_t n : {100000, 1500000}) {
    auto pts = torch::rand({n, 2}) * torch::tensor({1536.0f, 1024.0f});
    std::printf("kNN (k=8) %8lld points  %8.1f ms\n", (long long)n, median_ms([&] { knn_2d(pts, 8); }, 3));
  }
  const int W = 1536, H = 1024;
  View src{Intrinsics::from_hfov(1.1, W, H), Pose::Identity()}, tgt = src;
  tgt.T_cw(0, 3) = -0.3;
  auto depth = 2.0 + torch::rand({H, W});
  std::printf("projected mask %dx%d   %8.1f ms\n", W, H,
              median_ms(
                  [&] {
                    projected_mask(depth, torch::ones({H, W}), src, tgt, 2);
                  },
                  3));
  return 0;
}

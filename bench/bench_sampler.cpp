// Benchmark: geometry-guided sampling of 1.5M supports from a 1536x1024 depth map (and smaller sizes).
#include <chrono>
#include <cstdio>

#include <torch/torch.h>

#include "core/progress.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "sampler/sampler.h"

using namespace isplat;

namespace {
// A room-like depth map: back wall, floor, a box, and a depth discontinuity.
torch::Tensor room_depth(int64_t H, int64_t W, double f) {
  auto v = (torch::arange(H, torch::kFloat32) + 0.5).view({H, 1}).expand({H, W});
  auto u = (torch::arange(W, torch::kFloat32) + 0.5).view({1, W}).expand({H, W});
  auto y = (v - H / 2.0) / f;  // ray slope downwards
  auto wall = torch::full({H, W}, 6.0f);
  auto floor = torch::where(y > 0.02, 1.5 / y, torch::full({H, W}, 1e9f));
  auto depth = torch::minimum(wall, floor);
  auto box = (u > W * 0.3) & (u < W * 0.5) & (v > H * 0.4) & (v < H * 0.8);
  return torch::where(box, torch::full({H, W}, 3.0f), depth).contiguous();
}

// Median of 7 samplings; with `normals`, plain and with-normals samplings alternate, so both see the same machine
// state and the difference is the normals' cost.
void run(int64_t W, int64_t H, int64_t budget, const std::string& mode, bool normals = false) {
  const double f = 0.8 * W;
  auto depth = room_depth(H, W, f);
  auto valid = torch::ones({H, W});
  auto K = make_K(f, f, W / 2.0, H / 2.0);
  auto image = torch::rand({3, H, W});
  SamplerOptions o;
  o.mode = mode;
  o.budget = budget;
  o.max_budget = budget;
  std::vector<double> ms, ms_normals;
  int64_t count = 0;
  sample_supports(depth, valid, K, image, o, 1);  // warm-up: first-touch page faults, thread pool
  for (int r = 0; r < 7; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    count = sample_supports(depth, valid, K, image, o, 1).count();
    ms.push_back(ms_since(t0));
    if (!normals) continue;
    t0 = std::chrono::steady_clock::now();
    sample_supports(depth, valid, K, image, o, 1, /*normals=*/true);
    ms_normals.push_back(ms_since(t0));
  }
  std::sort(ms.begin(), ms.end());
  std::printf("%-12s %5lldx%-5lld supports %8lld  median %8.1f ms  (%.1f M supports/s)", mode.c_str(), (long long)W,
              (long long)H, (long long)count, ms[3], count / ms[3] / 1e3);
  if (normals) {
    std::sort(ms_normals.begin(), ms_normals.end());
    std::printf("  with normals %8.1f ms (+%.1f)", ms_normals[3], ms_normals[3] - ms[3]);
  }
  std::printf("\n");
}
}  // namespace

int main(int argc, char** argv) {
  configure_threads(argc > 1 ? std::atoll(argv[1]) : 0);
  std::printf("sampler benchmark, %d threads\n", at::get_num_threads());
  run(256, 192, 100000, "area", true);
  run(512, 384, 400000, "area");
  run(1536, 1024, 1500000, "area", true);
  run(1536, 1024, 1500000, "vertex_face");
  run(1536, 1024, 0, "pixel");
  return 0;
}

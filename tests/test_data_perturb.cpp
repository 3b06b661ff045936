// Depth perturbations shared by the stability suite and training: the smooth warp and the per-tuple draw of
// training's depth errors have the requested strength and are deterministic for a seed.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <cmath>

#include "data/perturb.h"

using namespace isplat;

TEST_CASE("data: depth_warp is a smooth log-depth field of the requested sigma, fixed by the seed", "[data][perturb]") {
  const int64_t H = 48, W = 64;
  const auto depth = torch::full({H, W}, 3.0f), valid = torch::ones({H, W});
  PerturbOptions o;
  o.depth_warp = 0.2;
  o.depth_warp_cells = 4;
  CHECK(o.any_depth());
  const auto a = perturb_depth(depth, valid, o, 7), b = perturb_depth(depth, valid, o, 7);
  CHECK(torch::equal(a.depth, b.depth));
  CHECK_FALSE(torch::equal(a.depth, perturb_depth(depth, valid, o, 8).depth));
  CHECK(torch::equal(a.valid, valid));  // a warp never invalidates depth
  const auto log_ratio = torch::log(a.depth / depth);
  // Smooth: one pixel's step is a small part of the field's range (nodes 16 px apart, |step| ≤ range / 16).
  const double range = (log_ratio.max() - log_ratio.min()).item<double>();
  const double step = (log_ratio.narrow(1, 1, W - 1) - log_ratio.narrow(1, 0, W - 1)).abs().max().item<double>();
  CHECK(range > 0.05);
  CHECK(step < range / 8);
  // The grid's corner node is the pixel (0, 0): over many seeds its log offset has sigma 0.2 and mean 0.
  std::vector<double> corner;
  for (uint64_t seed = 0; seed < 600; ++seed)
    corner.push_back(std::log(perturb_depth(depth, valid, o, seed).depth[0][0].item<double>() / 3.0));
  const auto c = torch::tensor(corner);
  CHECK(c.std().item<double>() == Approx(0.2).epsilon(0.1));  // 600 samples: within 10%
  CHECK(std::abs(c.mean().item<double>()) < 0.03);
}

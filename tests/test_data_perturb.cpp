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

TEST_CASE("data: draw_depth_error draws scale and blur per tuple with the requested spread", "[data][perturb]") {
  DepthErrorOptions off;
  CHECK_FALSE(off.any());
  CHECK_FALSE(draw_depth_error(off, 3).any_depth());
  DepthErrorOptions o;
  o.scale_sigma = 0.25;
  o.warp_sigma = 0.1;
  o.warp_cells = 5;
  o.blur_px = 2.0;
  CHECK(o.any());
  const PerturbOptions p = draw_depth_error(o, 11), q = draw_depth_error(o, 11);
  CHECK(p.depth_scale == q.depth_scale);
  CHECK(p.depth_blur_px == q.depth_blur_px);
  CHECK(p.depth_warp == 0.1);
  CHECK(p.depth_warp_cells == 5);
  std::vector<double> log_scale, blur;
  for (uint64_t seed = 0; seed < 800; ++seed) {
    const PerturbOptions d = draw_depth_error(o, seed);
    log_scale.push_back(std::log(d.depth_scale));
    blur.push_back(d.depth_blur_px);
  }
  const auto s = torch::tensor(log_scale), b = torch::tensor(blur);
  CHECK(s.std().item<double>() == Approx(0.25).epsilon(0.1));
  CHECK(std::abs(s.mean().item<double>()) < 0.03);
  CHECK(b.min().item<double>() >= 0.0);
  CHECK(b.max().item<double>() <= 2.0);
  CHECK(b.mean().item<double>() == Approx(1.0).epsilon(0.1));
}

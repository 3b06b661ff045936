// Losses: perceptual + Gram on the real SqueezeNet weights (when present), its loud switch-off, the scale
// hinge, neighbour smoothness, normal coherence, the rendered-depth gradient term, and the grid-hash kNN against
// brute force.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "loss/knn.h"
#include "loss/losses.h"
#include "loss/objective.h"
#include "nets/feature_net.h"
#include "support/test_util.h"

using namespace isplat;

TEST_CASE("knn: grid hash agrees with brute force", "[loss][knn]") {
  torch::manual_seed(3);
  for (int64_t n : {1, 5, 9, 2000}) {
    auto pts = torch::rand({n, 2}) * torch::tensor({256.0f, 192.0f});
    if (n == 2000) pts.narrow(0, 0, 500).mul_(0.1f);  // a dense cluster and a sparse rest
    const int64_t k = 8;
    auto nb = knn_2d(pts, k);
    REQUIRE(nb.sizes() == torch::IntArrayRef({n, k}));
    auto d = torch::cdist(pts, pts, 2.0, 2);  // compute_mode 2: no matmul shortcut, exact differences
    d.fill_diagonal_(std::numeric_limits<float>::infinity());
    const int64_t m = std::min<int64_t>(k, n - 1);
    auto expect = std::get<0>(torch::sort(d, 1)).narrow(1, 0, m);
    auto got = d.gather(1, nb.narrow(1, 0, m));
    CHECK(torch::allclose(got, expect, 1e-5, 1e-5));
    if (m < k) CHECK(torch::equal(nb.select(1, k - 1), torch::arange(n)));  // padding repeats the point itself
  }
}

TEST_CASE("losses: scale hinge is zero inside the bounds and linear outside", "[loss]") {
  auto depth = torch::tensor({2.0, 2.0, 2.0}, torch::kFloat64);
  auto scales = torch::tensor({{2 * std::exp(-5.0), 2 * std::exp(-5.0), 2 * std::exp(-5.0)},
                               {2 * std::exp(-9.0), 2 * std::exp(-5.0), 2 * std::exp(-5.0)},
                               {2 * std::exp(-1.0), 2 * std::exp(-5.0), 2 * std::exp(-5.0)}},
                              torch::kFloat64);
  CHECK(scale_range_loss(scales.narrow(0, 0, 1), depth.narrow(0, 0, 1), -8, -3).item<double>() ==
        Approx(0.0).margin(1e-12));
  // Below by 1 and above by 2, over 9 entries.
  CHECK(scale_range_loss(scales, depth, -8, -3).item<double>() == Approx(3.0 / 9.0));
}

TEST_CASE("losses: smoothness penalizes neighbours that differ", "[loss]") {
  auto s = torch::full({4, 3}, 0.1), a = torch::full({4}, 0.5);
  auto nb = torch::tensor({{1, 2}, {0, 3}, {3, 0}, {2, 1}});
  CHECK(smoothness_loss(s, a, nb).item<double>() == Approx(0.0));
  s[0].fill_(0.1 * std::exp(1.0));
  a[0] = 0.9;
  // Pairs involving 0: (0,1), (0,2), (1,0), (2,0): each |dlog s| = 3, |da| = 0.4; 8 pairs in all.
  CHECK(smoothness_loss(s, a, nb).item<double>() == Approx(4 * 3.4 / 8));
}

TEST_CASE("losses: Gram matrix normalization", "[loss]") {
  auto f = torch::ones({1, 2, 3, 4});
  f[0][1].mul_(2.0);
  auto g = gram_matrix(f);
  CHECK(g[0][0][0].item<float>() == Approx(12.0 / 24));
  CHECK(g[0][0][1].item<float>() == Approx(24.0 / 24));
  CHECK(g[0][1][1].item<float>() == Approx(48.0 / 24));
}

TEST_CASE("losses: the perceptual term is off, loudly, without weights", "[loss]") {
  LossOptions o;
  o.perceptual_weights = "/nonexistent/squeezenet.safetensors";
  PerceptualLoss p(o);
  CHECK_FALSE(p.enabled());
  CHECK(p.describe() == "off");
  o.allow_random_perceptual = true;
  PerceptualLoss r(o);
  REQUIRE(r.enabled());
  CHECK(r.describe() == "squeezenet1_1 (random)");
}

TEST_CASE("losses: perceptual + Gram on the real SqueezeNet weights", "[loss]") {
  ISPLAT_REQUIRE_WEIGHTS();
  LossOptions o;
  o.perceptual_weights = test::squeezenet_weights();
  PerceptualLoss p(o);
  REQUIRE(p.enabled());
  CHECK(p.describe() == "squeezenet1_1 (pretrained)");
  torch::manual_seed(0);
  auto y = torch::rand({1, 3, 64, 64});
  CHECK(p(y, y).item<float>() == Approx(0.0f).margin(1e-7));
  auto x = (y + 0.2 * torch::randn_like(y)).clamp(0, 1).requires_grad_(true);
  auto loss = p(x, y);
  CHECK(loss.item<float>() > 0.0f);
  loss.backward();
  CHECK(x.grad().abs().sum().item<float>() > 0.0f);
  // More noise, larger loss.
  auto x2 = (y + 0.4 * torch::randn_like(y)).clamp(0, 1);
  CHECK(p(x2, y).item<float>() > loss.item<float>());
}

TEST_CASE("losses: the depth loss separates shape (scale-invariant) from the global metric scale", "[loss]") {
  torch::manual_seed(2);
  const auto depth = torch::rand({2, 8, 8}) * 5 + 0.5;
  const auto valid = torch::ones({2, 8, 8});
  const auto shape = torch::log(depth) + 0.1 * torch::randn({2, 8, 8});
  LossOptions o;
  o.depth_lambda = 1.0;  // pure shape
  o.depth_scale = 1.0;
  o.depth_l1 = 0.0;
  const auto a = depth_log_losses(shape, depth, valid, o);
  const auto b = depth_log_losses(shape + std::log(3.0), depth, valid, o);  // the same shape, 3x too far
  CHECK(b.at("silog").item<double>() == Approx(a.at("silog").item<double>()).epsilon(1e-4));
  CHECK(b.at("scale").item<double>() ==
        Approx(std::log(3.0) + (shape - torch::log(depth)).mean().item<double>()).epsilon(1e-4));
  CHECK(b.at("total").item<double>() > a.at("total").item<double>());
  CHECK_THROWS_WITH(depth_log_losses(shape, depth, torch::zeros({2, 8, 8}), o), Catch::Contains("without valid depth"));
  CHECK(a.count("sky") == 0);  // off by default: pixels without depth are not supervised
}

TEST_CASE("losses: the sky term pushes pixels without depth beyond depth_sky_m, and only those", "[loss]") {
  const auto depth = torch::full({1, 4, 4}, 2.0);
  auto valid = torch::ones({1, 4, 4});
  valid[0][0] = 0;  // the top row is sky
  LossOptions o;
  o.depth_sky = 1.0;
  o.depth_sky_m = 100.0;
  auto pred = torch::full({1, 4, 4}, std::log(2.0));  // exact where valid; the sky at 2 m
  pred.requires_grad_(true);
  const auto t = depth_log_losses(pred, depth, valid, o);
  CHECK(t.at("sky").item<double>() == Approx(std::log(50.0)));
  CHECK(t.at("total").item<double>() == Approx(std::log(50.0)).margin(1e-5));
  t.at("total").backward();
  const auto g = pred.grad()[0];
  CHECK((g[0] < 0).all().item<bool>());                        // descent raises the sky's depth ...
  CHECK(g.narrow(0, 1, 3).abs().max().item<double>() < 1e-6);  // ... and leaves exact valid pixels alone
  // A sky already beyond depth_sky_m costs nothing; neither does a batch without sky.
  const auto far = torch::where(valid > 0, torch::full({1, 4, 4}, std::log(2.0)), torch::full({1, 4, 4}, 5.0));
  CHECK(depth_log_losses(far, depth, valid, o).at("sky").item<double>() == 0.0);
  CHECK(depth_log_losses(pred.detach(), depth, torch::ones({1, 4, 4}), o).at("sky").item<double>() == 0.0);
}

TEST_CASE("losses: the objective's total is the paper's weighted sum of its terms", "[loss]") {
  LossOptions o;
  o.perceptual = 0;
  o.rgb = 2.0;
  o.knn = 2;
  ObjectiveInput in;
  in.render = torch::full({1, 3, 2, 3}, 0.5);
  in.target = torch::full({1, 3, 2, 3}, 0.25);
  in.mask = torch::ones({1, 1, 2, 3});
  in.gaussians.scales = torch::full({4, 3}, 0.02);
  in.gaussians.scales[0].fill_(1.0);  // outside the hinge's bounds at 2 m: a non-zero scale term
  in.gaussians.opacities = torch::full({4}, 0.5);
  in.depth = torch::full({4}, 2.0);
  in.support_uv = torch::rand({4, 2});
  GaussianObjective objective(o);
  auto t = objective.terms(in);
  objective.add_total(t);
  CHECK(t.size() == 5);  // l1, perceptual, scale, smooth and the total
  CHECK(t.at("l1").item<double>() == Approx(0.25).epsilon(1e-5));
  CHECK(t.at("scale").item<double>() > 0);
  CHECK(t.at("perceptual").item<double>() == 0.0);
  CHECK(t.at("total").item<double>() ==
        Approx(2.0 * 0.25 + o.reg * (o.scale * t.at("scale").item<double>() + o.smooth * t.at("smooth").item<double>()))
            .epsilon(1e-5));
}

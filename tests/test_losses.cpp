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

TEST_CASE("losses: normal coherence asks flat neighbours to share a normal, and ignores round ones", "[loss]") {
  // Four flat Gaussians (shortest axis z in their own frame); 0 and 1 unrotated, 2 and 3 turned 90 degrees
  // about x, so their normal is the y axis. Neighbours: 0-1, 2-3 (agree), and 0-2, 1-3 (orthogonal).
  auto s = torch::tensor({{0.1, 0.1, 0.01}, {0.1, 0.1, 0.01}, {0.1, 0.1, 0.01}, {0.1, 0.1, 0.01}});
  const double h = std::sqrt(0.5);
  auto q = torch::tensor({{1.0, 0.0, 0.0, 0.0}, {-2.0, 0.0, 0.0, 0.0}, {h, h, 0.0, 0.0}, {h, h, 0.0, 0.0}})
               .requires_grad_(true);
  auto nb = torch::tensor({{1, 2}, {0, 3}, {3, 0}, {2, 1}});
  auto loss = normal_coherence_loss(s, q, nb);
  // Half the 8 pairs are orthogonal (1 - 0) at flatness weight 0.9 * 0.9; q's sign and norm do not matter.
  CHECK(loss.item<double>() == Approx(4 * 0.81 / 8).epsilon(1e-5));
  loss.backward();
  CHECK(q.grad().abs().sum().item<double>() > 0);
  CHECK(s.grad().defined() == false);
  // Equal normals cost nothing; round Gaussians cost nothing however they are turned.
  auto same = torch::tensor({{1.0, 0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}});
  CHECK(normal_coherence_loss(s, same, nb).item<double>() == Approx(0.0).margin(1e-7));
  CHECK(normal_coherence_loss(torch::full({4, 3}, 0.1), q.detach(), nb).item<double>() == Approx(0.0).margin(1e-7));
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

TEST_CASE("losses: the depth-gradient term sees steps on smooth reference surfaces, and nothing else", "[loss]") {
  // One 2x3 target at 2 m; the rendered depth (alpha 1) steps to 2.2 m in the bottom-right pixel.
  auto ref = torch::full({1, 2, 3}, 2.0, torch::kFloat64);
  const auto valid = torch::ones({1, 2, 3}, torch::kFloat64);
  auto alpha = torch::ones({1, 1, 2, 3}, torch::kFloat64);
  auto mask = torch::ones({1, 1, 2, 3}, torch::kFloat64);
  auto depth = torch::full({1, 1, 2, 3}, 2.0, torch::kFloat64);
  depth[0][0][1][2] = 2.2;
  depth.requires_grad_(true);
  // 7 neighbour pairs (3 down, 4 right); the step crosses two of them.
  const auto l = depth_gradient_loss(depth, alpha, ref, valid, mask, 0.05);
  CHECK(l.item<double>() == Approx(2 * std::log(1.1) / 7));
  l.backward();
  CHECK(depth.grad()[0][0][1][2].item<double>() > 0);  // descent pulls the step back towards its neighbours
  CHECK(depth.grad()[0][0][0][0].item<double>() == 0.0);
  // A rendered depth that follows a smooth slope, at any global scale, costs nothing.
  const auto slope = torch::linspace(2.0, 2.1, 3, torch::kFloat64).view({1, 1, 3}).expand({1, 2, 3}).contiguous();
  CHECK(depth_gradient_loss(3 * slope.unsqueeze(1), alpha, slope, valid, mask, 0.05).item<double>() ==
        Approx(0.0).margin(1e-12));
  // Where the reference has the same step, it is an edge: those pairs are skipped (5 smooth pairs remain, exact).
  ref[0][1][2] = 2.2;
  CHECK(depth_gradient_loss(depth.detach(), alpha, ref, valid, mask, 0.05).item<double>() == Approx(0.0).margin(1e-12));
  ref[0][1][2] = 2.0;
  // A hole (alpha < 0.5), a pixel outside the mask or without reference depth drops its pairs.
  for (int which = 0; which < 3; ++which) {
    auto a = alpha.clone(), m = mask.clone(), v = valid.clone();
    (which == 0 ? a[0][0][1][2] : which == 1 ? m[0][0][1][2] : v[0][1][2]).fill_(which == 0 ? 0.4 : 0.0);
    CHECK(depth_gradient_loss(depth.detach() * (which == 0 ? a : alpha), a, ref, v, m, 0.05).item<double>() ==
          Approx(0.0).margin(1e-12));
  }
  // A non-finite reference outside the valid pixels reaches neither the loss nor its gradient.
  {
    auto bad = ref.clone();
    auto v = valid.clone();
    bad[0][0][0] = std::numeric_limits<double>::quiet_NaN();
    v[0][0][0] = 0;
    auto d = depth.detach().clone().requires_grad_(true);
    const auto lb = depth_gradient_loss(d, alpha, bad, v, mask, 0.05);
    lb.backward();
    CHECK(std::isfinite(lb.item<double>()));
    CHECK(torch::isfinite(d.grad()).all().item<bool>());
  }
  // Rendered depth is a sum: the term divides by alpha, so a half-transparent but right surface is no step.
  auto half = alpha.clone();
  half[0][0][0][0] = 0.6;
  auto sum = torch::full({1, 1, 2, 3}, 2.0, torch::kFloat64) * half;
  CHECK(
      depth_gradient_loss(sum, half, torch::full({1, 2, 3}, 2.0, torch::kFloat64), valid, mask, 0.05).item<double>() ==
      Approx(0.0).margin(1e-12));
  CHECK_THROWS_WITH(depth_gradient_loss(depth.detach(), alpha, ref.narrow(2, 0, 2), valid, mask, 0.05),
                    Catch::Contains("reference depth"));
}

TEST_CASE("losses: the objective adds depth_grad only when weighted, and asks for the depths it needs", "[loss]") {
  LossOptions o;
  o.perceptual = 0;
  o.smooth = 0;
  o.depth_grad = 2.0;
  GaussianObjective objective(o);
  ObjectiveInput in;
  in.render = torch::full({1, 3, 2, 3}, 0.5);
  in.target = torch::full({1, 3, 2, 3}, 0.5);
  in.mask = torch::ones({1, 1, 2, 3});
  in.gaussians.scales = torch::full({4, 3}, 0.02);
  in.gaussians.opacities = torch::full({4}, 0.5);
  in.depth = torch::full({4}, 2.0);
  in.support_uv = torch::rand({4, 2});
  CHECK_THROWS_WITH(objective.terms(in), Catch::Contains("loss.depth_grad"));
  in.render_alpha = torch::ones({1, 1, 2, 3});
  in.render_depth = torch::full({1, 1, 2, 3}, 2.0);
  in.render_depth[0][0][1][2] = 2.2;
  in.target_depth = torch::full({1, 2, 3}, 2.0);
  in.target_valid = torch::ones({1, 2, 3});
  auto t = objective.terms(in);
  objective.add_total(t);
  CHECK(t.at("depth_grad").item<double>() == Approx(2 * std::log(1.1) / 7).epsilon(1e-5));
  CHECK(t.at("total").item<double>() ==
        Approx(2.0 * t.at("depth_grad").item<double>() + o.reg * o.scale * t.at("scale").item<double>()));
}

TEST_CASE("losses: the opacity sparsity term is the mean unclamped opacity, weighted into the total, pushing it down",
          "[loss]") {
  LossOptions o;
  o.perceptual = 0;
  o.smooth = 0;
  ObjectiveInput in;
  in.render = torch::full({1, 3, 2, 3}, 0.5);
  in.target = torch::full({1, 3, 2, 3}, 0.5);
  in.mask = torch::ones({1, 1, 2, 3});
  in.gaussians.scales = torch::full({4, 3}, 0.02);
  in.gaussians.opacities = torch::full({4}, 0.99);  // clamped: the term must not read these
  in.opacity_unclamped = torch::tensor({0.1, 0.2, 0.3, 0.8}).requires_grad_(true);
  in.depth = torch::full({4}, 2.0);
  in.support_uv = torch::rand({4, 2});
  {  // off by default: the term stays zero and has no say in the total
    GaussianObjective objective(o);
    auto t = objective.terms(in);
    objective.add_total(t);
    CHECK(t.at("opacity").item<double>() == 0.0);
    CHECK(t.at("total").item<double>() == Approx(o.reg * o.scale * t.at("scale").item<double>()).margin(1e-12));
  }
  o.opacity = 0.5;
  GaussianObjective objective(o);
  auto t = objective.terms(in);
  objective.add_total(t);
  CHECK(t.at("opacity").item<double>() == Approx(0.35));
  CHECK(t.at("total").item<double>() == Approx(0.5 * 0.35 + o.reg * o.scale * t.at("scale").item<double>()));
  t.at("total").backward();
  const auto g = in.opacity_unclamped.grad();
  REQUIRE(g.defined());
  CHECK(torch::allclose(g, torch::full({4}, 0.5 / 4)));
  in.opacity_unclamped = torch::Tensor();
  CHECK_THROWS_WITH(objective.terms(in), Catch::Contains("loss.opacity"));
}

// Depth priors: dataset passthrough, TorchScript contract and errors, sparse-prompt alignment and its
// determinism, the learned net's shapes.
#include <catch2/catch.hpp>

#include <torch/script.h>
#include <torch/torch.h>

#include <tuple>
#include <utility>

#include "core/config.h"
#include "core/error.h"
#include "geometry/camera_torch.h"
#include "io/safetensors.h"
#include "prior/depth_prior.h"
#include "prior/learned_depth.h"
#include "support/test_util.h"

using namespace isplat;

namespace {
// Smooth positive depth field over H x W.
torch::Tensor scene_depth(int64_t H, int64_t W) {
  auto y = torch::linspace(0, 1, H).view({H, 1}), x = torch::linspace(0, 1, W).view({1, W});
  return 2.0 + 1.5 * x + 0.5 * torch::sin(3.0 * y) * x;
}
// Planar depth of a camera `height` m above a flat floor, pitched down by `pitch` radians; pixels above the
// horizon see a fronto-parallel wall at 8 m (no floor there).
torch::Tensor floor_depth(int64_t H, int64_t W, const torch::Tensor& K, double height, double pitch) {
  auto d = torch::empty({H, W});
  const double fy = K[1][1].item<double>(), cy = K[1][2].item<double>();
  const double up_y = -std::cos(pitch), up_z = -std::sin(pitch);  // world up in the OpenCV camera frame
  for (int64_t i = 0; i < H; ++i) {
    const double along_up = up_y * (i + 0.5 - cy) / fy + up_z;  // ray (x, y, 1) against up: x plays no part
    d[i].fill_(along_up < -1e-3 ? std::min(8.0, height / -along_up) : 8.0);
  }
  return d;
}
std::string save_module(const std::string& dir, const std::string& name, const std::string& body) {
  torch::jit::Module m(name);
  m.define(body);
  const std::string path = dir + "/" + name + ".pt";
  m.save(path);
  return path;
}
// A tiny learned prior (width 8), untrained: seed torch before make_depth_prior to fix its weights.
PriorOptions tiny_learned(bool focal_normalized) {
  PriorOptions o;
  o.type = "learned";
  o.learned_width = 8;
  o.learned_focal = focal_normalized;
  return o;
}
}  // namespace

TEST_CASE("prior: dataset depth passes through with its mask and an estimated K", "[prior]") {
  PriorOptions o;
  auto prior = make_depth_prior(o);
  PriorInput in;
  in.image = torch::rand({3, 24, 32});
  in.depth = scene_depth(24, 32);
  in.depth[0][0] = std::numeric_limits<float>::quiet_NaN();
  auto out = prior->predict(in);
  CHECK(out.valid[0][0].item<float>() == 0.0f);
  CHECK(out.depth[0][0].item<float>() == 0.0f);
  CHECK(out.valid.sum().item<float>() == 24 * 32 - 1);
  CHECK(out.K[0][0].item<float>() == Approx(16.0 / std::tan(M_PI / 6)));  // 60 degrees by default
  in.depth = torch::Tensor();
  CHECK_THROWS_WITH(prior->predict(in), Catch::Contains("needs the frame's depth"));
}

TEST_CASE("prior: a TorchScript model follows the documented contract", "[prior]") {
  const auto dir = test::temp_dir("prior_ts");
  PriorOptions o;
  o.type = "torchscript";
  o.torchscript = save_module(dir, "good", "def forward(self, x):\n    return x.mean(1, keepdim=True) * 2.0 + 1.0\n");
  auto prior = make_depth_prior(o);
  PriorInput in;
  in.image = torch::full({3, 16, 20}, 0.5f);
  auto out = prior->predict(in);
  CHECK(out.depth.sizes() == torch::IntArrayRef({16, 20}));
  CHECK(out.depth[3][4].item<float>() == Approx(2.0f));
  o.torchscript = save_module(dir, "bad", "def forward(self, x):\n    return x[:, :, ::2, :]\n");
  auto bad = make_depth_prior(o);
  CHECK_THROWS_WITH(bad->predict(in), Catch::Contains("returned shape [1, 3, 8, 20], expected [1, 1, 16, 20]"));
  o.torchscript = dir + "/none.pt";
  CHECK_THROWS_WITH(make_depth_prior(o), Catch::Contains("none.pt: no such file"));
}

TEST_CASE("prior: sparse prompts align a wrong-scale monocular depth", "[prior]") {
  const int64_t H = 48, W = 64;
  auto truth = scene_depth(H, W);
  // A monocular prior off by an affine map in inverse depth and a smooth multiplicative bias.
  auto inv = (1.0 / truth - 0.05) / 2.0;
  auto mono = 1.0 / inv * (1.0 + 0.1 * torch::linspace(-1, 1, H).view({H, 1}));
  auto prompts = draw_prompts(truth, torch::ones({H, W}), 300, 0.0, 7);
  SparsePriorOptions smooth;
  smooth.bandwidth = smooth.finest = 0.15;  // one smooth level
  auto aligned = align_to_prompts(mono, prompts, smooth);
  const double before = ((mono - truth).abs() / truth).mean().item<double>();
  const double after = ((aligned - truth).abs() / truth).mean().item<double>();
  INFO("relative error before " << before << " after " << after);
  CHECK(before > 0.5);
  CHECK(after < 0.02);
  // Prompts are deterministic in the seed, and noise perturbs them.
  CHECK(torch::equal(prompts, draw_prompts(truth, torch::ones({H, W}), 300, 0.0, 7)));
  auto noisy = draw_prompts(truth, torch::ones({H, W}), 300, 0.05, 7);
  CHECK(torch::equal(noisy.narrow(1, 0, 2), prompts.narrow(1, 0, 2)));
  CHECK_FALSE(torch::allclose(noisy.select(1, 2), prompts.select(1, 2)));
  // The sweep's two knobs have the requested effect: exactly `count` distinct pixels (all of them when fewer are
  // valid), and multiplicative noise d(1 + eps) with eps of the requested sigma (1500 draws: within 10%).
  for (int64_t count : {1500, 500, 100, 20}) {
    const auto drawn = draw_prompts(truth, torch::ones({H, W}), count, 0.0, 3);
    REQUIRE(drawn.size(0) == count);
    const auto pixel = (drawn.select(1, 1) - 0.5) * W + (drawn.select(1, 0) - 0.5);
    CHECK(std::get<0>(at::_unique(pixel)).numel() == count);
  }
  auto few = torch::zeros({H, W});
  few.view({-1}).narrow(0, 100, 37).fill_(1);  // 37 valid pixels
  CHECK(draw_prompts(truth, few, 1500, 0.0, 3).size(0) == 37);
  for (double sigma : {0.01, 0.03, 0.05}) {
    const auto clean = draw_prompts(truth, torch::ones({H, W}), 1500, 0.0, 11);
    const auto noised = draw_prompts(truth, torch::ones({H, W}), 1500, sigma, 11);
    REQUIRE(torch::equal(noised.narrow(1, 0, 2), clean.narrow(1, 0, 2)));  // the same pixels, only z moves
    const auto eps = noised.select(1, 2) / clean.select(1, 2) - 1;
    CHECK(eps.std().item<double>() == Approx(sigma).epsilon(0.1));
    CHECK(std::abs(eps.mean().item<double>()) < 4 * sigma / std::sqrt(1500.0));
  }
  // The full prior with no monocular net densifies from the prompts alone.
  PriorOptions o;
  o.type = "sparse";
  o.sparse.mono = "none";
  o.sparse.prompts = 1500;
  auto prior = make_depth_prior(o);
  PriorInput in;
  in.image = torch::rand({3, H, W});
  in.depth = truth;
  auto out = prior->predict(in);
  CHECK(((out.depth - truth).abs() / truth).mean().item<double>() < 0.05);
}

TEST_CASE("prior: sparse alignment refines coarse to fine, and cross-validation keeps noisy prompts smooth",
          "[prior]") {
  const int64_t H = 96, W = 128;
  auto truth = scene_depth(H, W);
  // A monocular error at a 16-pixel period: finer than the coarsest kernel (12.8 px), coarser than the
  // prompts' spacing (about 3 px).
  auto yy = torch::arange(H).view({H, 1}).to(torch::kFloat32), xx = torch::arange(W).view({1, W}).to(torch::kFloat32);
  auto mono = truth * (1.0 + 0.3 * torch::sin(yy * (2 * M_PI / 16)) * torch::sin(xx * (2 * M_PI / 16)));
  auto error = [&](const torch::Tensor& d) { return ((d - truth).abs() / truth).mean().item<double>(); };
  auto clean = draw_prompts(truth, torch::ones({H, W}), 4000, 0.0, 3);
  SparsePriorOptions o;
  o.bandwidth = 0.08, o.finest = 0.005;
  o.cross_validate = false;
  o.depth_range = 0;  // the monocular error here is depth texture, which an edge-aware weight would respect
  int64_t levels = 0;
  const double all_levels = error(align_to_prompts(mono, clean, o, &levels));
  CHECK(levels == 5);  // 0.08, 0.04, 0.02, 0.01, 0.005
  SparsePriorOptions one = o;
  one.finest = one.bandwidth;
  const double one_level = error(align_to_prompts(mono, clean, one, &levels));
  CHECK(levels == 1);
  INFO("error: one level " << one_level << ", five levels " << all_levels);
  CHECK(one_level > 0.05);
  CHECK(all_levels < 0.3 * one_level);
  // Clean prompts: cross-validation refines (nearly) as far as it can.
  o.cross_validate = true;
  int64_t clean_levels = 0;
  const double clean_cv = error(align_to_prompts(mono, clean, o, &clean_levels));
  CHECK(clean_levels >= 4);
  CHECK(clean_cv < 1.2 * all_levels);
  // Noisy prompts (30%): the finest levels would fit the noise; cross-validation stops earlier and does better.
  auto noisy = draw_prompts(truth, torch::ones({H, W}), 4000, 0.3, 3);
  int64_t noisy_levels = 0;
  const double noisy_cv = error(align_to_prompts(mono, noisy, o, &noisy_levels));
  o.cross_validate = false;
  const double noisy_all = error(align_to_prompts(mono, noisy, o));
  INFO("noisy prompts: cross-validated " << noisy_cv << " (" << noisy_levels << " levels), all levels " << noisy_all);
  CHECK(noisy_levels < clean_levels);
  CHECK(noisy_cv < noisy_all);
  // The prior refuses a finest width above the coarsest, naming both keys.
  PriorOptions bad;
  bad.type = "sparse";
  bad.sparse.mono = "none";
  bad.sparse.finest = 0.1;
  CHECK_THROWS_WITH(make_depth_prior(bad), Catch::Contains("prior.sparse.finest (0.1) must not exceed "
                                                           "prior.sparse.bandwidth (0.08)"));
}

// A wall sloping from 5 to 7 m with an object at 2 m over columns [first, first + width). The monocular depth has
// the right shape but each surface's own scale error (object x1.25, wall x0.8), so no global map in inverse depth
// fixes both. Returns {truth, mono}.
namespace {
std::pair<torch::Tensor, torch::Tensor> wall_and_object(int64_t H, int64_t W, int64_t first, int64_t width) {
  auto truth = (5.0 + 2.0 * torch::arange(H).to(torch::kFloat32) / H).view({H, 1}).expand({H, W}).contiguous();
  truth.narrow(1, first, width).fill_(2.0f);
  auto mono = truth * 0.8f;
  mono.narrow(1, first, width).fill_(2.0f * 1.25f);
  return {truth, mono};
}

// One level 9 px wide (on a 64x96 image), all of it used: the blur reaches well across the object's edges.
SparsePriorOptions one_level(double depth_range) {
  SparsePriorOptions o;
  o.bandwidth = o.finest = 0.08;
  o.cross_validate = false;
  o.depth_range = depth_range;
  return o;
}
}  // namespace

TEST_CASE("prior: the edge-aware residual field keeps a prompt's correction on its own surface", "[prior]") {
  const int64_t H = 64, W = 96;
  // A box over columns 32..63: a smooth residual field blurs the two corrections across its edges.
  torch::Tensor truth, mono;
  std::tie(truth, mono) = wall_and_object(H, W, 32, 32);
  auto prompts = draw_prompts(truth, torch::ones({H, W}), 400, 0.0, 5);
  SparsePriorOptions o = one_level(0);
  auto band_error = [&](const torch::Tensor& d) {  // mean relative error within 6 px of either edge
    auto err = (d - truth).abs() / truth;
    return torch::cat({err.narrow(1, 26, 12), err.narrow(1, 58, 12)}, 1).mean().item<double>();
  };
  const double plain = band_error(align_to_prompts(mono, prompts, o));
  o.depth_range = 0.1;
  auto edge_aware = align_to_prompts(mono, prompts, o);
  const double aware = band_error(edge_aware);
  INFO("relative error near the edges: plain " << plain << ", edge-aware " << aware);
  CHECK(plain > 0.025);
  CHECK(aware < 0.2 * plain);
  // Away from the edges it still agrees with the truth, and the output stays positive and finite.
  CHECK(((edge_aware - truth).abs() / truth).narrow(1, 0, 20).mean().item<double>() < 0.01);
  CHECK(torch::isfinite(edge_aware).all().item<bool>());
  CHECK((edge_aware > 0).all().item<bool>());
}

TEST_CASE("prior: a pole narrower than the field's grid keeps its own correction", "[prior]") {
  const int64_t H = 64, W = 96;
  // A 2-px pole (columns 47-48). The one level is 9 px wide and is computed on a 4-px grid whose samples
  // (u = 46, 50) all fall on the wall, so upsampling the grid alone gives the pole the wall's correction.
  torch::Tensor truth, mono;
  std::tie(truth, mono) = wall_and_object(H, W, 47, 2);
  auto prompts = draw_prompts(truth, torch::ones({H, W}), 1500, 0.0, 7);
  auto d = align_to_prompts(mono, prompts, one_level(0.1));
  const double pole = ((d - truth).abs() / truth).narrow(1, 47, 2).mean().item<double>();
  const double wall = ((d - truth).abs() / truth).narrow(1, 0, 40).mean().item<double>();
  INFO("relative error: pole " << pole << ", wall " << wall);
  CHECK(pole < 0.05);  // the wall's correction would leave it tens of percent off
  CHECK(wall < 0.01);
  // A range so small that its kernel would overflow is refused, naming the key.
  PriorOptions bad;
  bad.type = "sparse";
  bad.sparse.mono = "none";
  bad.sparse.depth_range = 1e-5;
  CHECK_THROWS_WITH(make_depth_prior(bad), Catch::Contains("prior.sparse.depth_range (1e-05) must be 0 (off)"));
}

TEST_CASE("prior: the learned net predicts positive metric depth at the input size", "[prior]") {
  LearnedDepthNet net(8);
  auto d = net->forward(torch::rand({2, 3, 40, 56}));
  CHECK(d.sizes() == torch::IntArrayRef({2, 1, 40, 56}));
  CHECK((d > 0).all().item<bool>());
  CHECK(d.mean().item<float>() == Approx(3.0f).epsilon(0.3));  // starts at room scale
}

namespace {
// The learned prior's contract for one architecture, plain and focal-normalized.
void check_learned_prior_contract(const std::string& arch) {
  test::QuietLogs quiet;
  const int64_t H = 48, W = 64;
  for (const bool focal : {false, true}) {
    INFO(arch << (focal ? " focal-normalized" : ""));
    PriorOptions o;
    o.type = "learned";
    o.learned_arch = arch;
    o.learned_focal = focal;
    o.learned_width = 8;
    o.learned_backbone = test::squeezenet_weights();
    auto prior = make_depth_prior(o);
    PriorInput in;
    in.image = torch::rand({3, H, W});
    in.K = make_K(50.0, 50.0, W / 2.0, H / 2.0, torch::kFloat32);
    const PriorOutput out = prior->predict(in);
    CHECK(out.depth.sizes() == torch::IntArrayRef({H, W}));
    CHECK(out.valid.sizes() == torch::IntArrayRef({H, W}));
    CHECK(torch::isfinite(out.depth).all().item<bool>());
    CHECK(((out.depth > 0) == (out.valid > 0)).all().item<bool>());  // invalid pixels are 0, never NaN
    CHECK(out.depth.max().item<double>() < 1e3);
    CHECK_THAT(prior->describe(), Catch::Contains(arch));
  }
}
}  // namespace

TEST_CASE("prior: the U-Net learned prior keeps the contract (shape, metric depth, invalid masked)", "[prior]") {
  check_learned_prior_contract("unet");
}

TEST_CASE("prior: the SqueezeNet learned prior keeps the contract", "[prior][weights]") {
  ISPLAT_REQUIRE_WEIGHTS();
  check_learned_prior_contract("squeeze");
}

TEST_CASE("prior: learned_sky_m marks depth at or beyond it as sky (invalid, 0)", "[prior]") {
  test::QuietLogs quiet;
  PriorOptions o = tiny_learned(false);
  PriorInput in;
  in.image = torch::rand({3, 32, 48});
  in.K = make_K(40.0, 40.0, 24.0, 16.0, torch::kFloat32);
  torch::manual_seed(5);
  const PriorOutput all = make_depth_prior(o)->predict(in);  // untrained: about 3 m everywhere
  CHECK(all.valid.min().item<float>() == 1.0f);
  o.learned_sky_m = all.depth.median().item<double>();  // half the pixels now count as sky
  torch::manual_seed(5);                                // the same untrained weights
  const PriorOutput cut = make_depth_prior(o)->predict(in);
  const auto sky = all.depth >= o.learned_sky_m;
  CHECK(sky.any().item<bool>());
  CHECK(torch::equal(cut.valid > 0, ~sky));
  CHECK(torch::equal(cut.depth, torch::where(sky, torch::zeros_like(all.depth), all.depth)));
}

TEST_CASE("prior: learned_flip_average is the geometric mean of the photo's and its mirror's depth", "[prior]") {
  test::QuietLogs quiet;
  const int64_t H = 32, W = 48;
  PriorOptions o = tiny_learned(true);
  PriorInput in, mirrored;
  in.image = torch::rand({3, H, W});
  in.K = make_K(40.0, 40.0, 20.0, 15.0, torch::kFloat32);
  mirrored.image = in.image.flip({2});
  mirrored.K = make_K(40.0, 40.0, W - 20.0, 15.0, torch::kFloat32);
  torch::manual_seed(5);
  auto plain = make_depth_prior(o);
  o.learned_flip_average = true;
  torch::manual_seed(5);  // the same untrained weights
  auto averaged = make_depth_prior(o);
  CHECK_THAT(averaged->describe(), Catch::Contains("flip-averaged"));
  const torch::Tensor a = plain->predict(in).depth, b = plain->predict(mirrored).depth.flip({1});
  REQUIRE_FALSE(torch::allclose(a, b, 1e-3, 0));  // the net is not mirror-symmetric, so averaging changes depth
  const PriorOutput out = averaged->predict(in);
  CHECK(torch::allclose(out.depth, torch::sqrt(a * b), 1e-5, 1e-6));
  CHECK(torch::equal(out.valid > 0, out.depth > 0));
  // Mirror-equivariant: the mirrored photo gets the mirrored depth.
  CHECK(torch::allclose(averaged->predict(mirrored).depth, out.depth.flip({1}), 1e-5, 1e-6));
}

TEST_CASE("prior: focal normalization scales depth with the focal length, exactly", "[prior]") {
  LearnedDepthNet net(LearnedDepthOptions{"unet", 8, true});
  torch::NoGradGuard g;
  const auto image = torch::rand({1, 3, 40, 56});
  const auto K1 = make_K(40.0, 40.0, 28.0, 20.0, torch::kFloat32).unsqueeze(0);
  const auto K2 = make_K(80.0, 80.0, 28.0, 20.0, torch::kFloat32).unsqueeze(0);
  const auto d1 = net->forward(image, K1), d2 = net->forward(image, K2);
  // Twice the focal length (half the field of view): the same picture shows a scene twice as far.
  CHECK(torch::allclose(d2, 2.0 * d1, 1e-5, 1e-6));
  CHECK_THROWS_WITH(net->forward(image), Catch::Contains("needs K"));
}

TEST_CASE("prior: the squeeze option trains only its decoder, the pretrained encoder stays frozen", "[prior]") {
  ISPLAT_REQUIRE_WEIGHTS();
  LearnedDepthNet net(LearnedDepthOptions{"squeeze", 8, false, test::squeezenet_weights()});
  int64_t count = 0;
  for (const auto& p : net->parameters()) count += p.numel();
  CHECK(count < 200000);  // the decoder only: SqueezeNet's 722k weights are not parameters
  const auto x = torch::rand({1, 3, 48, 64});
  const auto loss = net->forward_log(x).mean();
  loss.backward();
  CHECK(net->head->weight.grad().abs().sum().item<double>() > 0);
}

TEST_CASE("prior: floor_height_scale recovers the metric scale from the camera height", "[prior]") {
  const int64_t H = 96, W = 128;
  const auto K = estimate_K(W, H, 60.0);
  const auto truth = floor_depth(H, W, K, 1.6, 0.15);
  const auto ones = torch::ones({H, W});
  // A prior that sees the right shape at a third of the scale is put back at metric scale.
  CHECK(floor_height_scale(truth * 0.3, ones, K, 1.6) == Approx(1.0 / 0.3).epsilon(0.01));
  CHECK(floor_height_scale(truth, ones, K, 1.6) == Approx(1.0).epsilon(0.01));
  CHECK(floor_height_scale(truth, ones, K, 0.8) == Approx(0.5).epsilon(0.01));
  // Furniture in front of part of the floor (a fronto-parallel box at 2 m) does not move it.
  auto cluttered = truth.clone();
  cluttered.narrow(0, 60, 30).narrow(1, 10, 40).fill_(2.0);
  CHECK(floor_height_scale(cluttered * 2.0, ones, K, 1.6) == Approx(0.5).epsilon(0.01));
  // Invalid pixels are ignored whatever they hold (NaN, absurd depth).
  auto broken = truth.clone() * 0.5;
  auto valid = ones.clone();
  broken.narrow(0, 50, 40).narrow(1, 70, 50).fill_(std::numeric_limits<float>::quiet_NaN());
  broken.narrow(0, 70, 10).narrow(1, 0, 60).fill_(1e4);
  valid.narrow(0, 50, 40).narrow(1, 70, 50).zero_();
  valid.narrow(0, 70, 10).narrow(1, 0, 60).zero_();
  CHECK(floor_height_scale(broken, valid, K, 1.6) == Approx(2.0).epsilon(0.01));
  // No floor: a wall everywhere, a floor seen only in the upper half (the lower half is a wall), or no valid
  // pixel.
  CHECK(floor_height_scale(torch::full({H, W}, 5.0f), ones, K, 1.6) == 0.0);
  CHECK(floor_height_scale(truth.flip({0}), ones, K, 1.6) == 0.0);
  CHECK(floor_height_scale(truth, torch::zeros({H, W}), K, 1.6) == 0.0);
  CHECK_THROWS_WITH(floor_height_scale(truth, ones, K, 0.0), Catch::Contains("camera height must be positive"));
}

TEST_CASE("prior: camera_height_m sets a monocular prior's scale and keeps the contract", "[prior]") {
  const auto dir = test::temp_dir("prior_floor");
  const int64_t H = 72, W = 96;
  const auto K = estimate_K(W, H, 60.0);
  const auto truth = floor_depth(H, W, K, 1.6, 0.1);
  PriorInput in;
  in.image = (truth / 20.0).unsqueeze(0).repeat({3, 1, 1});  // the model reads depth / 20 off the image
  in.image[0][0][0] = 0.0f;                                  // one pixel the model leaves without depth
  in.K = K;
  PriorOptions o;
  o.type = "torchscript";
  o.torchscript = save_module(dir, "third", "def forward(self, x):\n    return x[:, 0:1] * (20.0 / 3.0)\n");
  const PriorOutput raw = make_depth_prior(o)->predict(in);
  CHECK_FALSE(raw.floor_scaled);
  CHECK(raw.depth[40][50].item<float>() == Approx(truth[40][50].item<float>() / 3.0f).epsilon(1e-4));
  o.camera_height_m = 1.6;
  const PriorOutput out = make_depth_prior(o)->predict(in);
  CHECK(out.floor_scaled);
  CHECK(out.depth.sizes() == torch::IntArrayRef({H, W}));
  CHECK(out.valid[0][0].item<float>() == 0.0f);
  CHECK(out.depth[0][0].item<float>() == 0.0f);
  const auto ok = out.valid > 0;
  CHECK(((out.depth.masked_select(ok) - truth.masked_select(ok)).abs() / truth.masked_select(ok)).max().item<double>() <
        0.01);
  // A frame without a floor keeps the model's own scale.
  in.image = torch::full({3, H, W}, 0.25f);
  const PriorOutput wall = make_depth_prior(o)->predict(in);
  CHECK_FALSE(wall.floor_scaled);
  CHECK(wall.depth[10][10].item<float>() == Approx(0.25f * 20.0f / 3.0f));
  // Priors with metric depth of their own ignore it (an experiment scores a run trained on a monocular prior
  // with dataset depth too): dataset depth passes through unscaled, and sparse prompts set the scale.
  test::QuietLogs quiet;
  in.image = (truth / 20.0).unsqueeze(0).repeat({3, 1, 1});
  in.depth = truth * 0.5;
  o.type = "dataset";
  const PriorOutput dataset = make_depth_prior(o)->predict(in);
  CHECK_FALSE(dataset.floor_scaled);
  CHECK(torch::allclose(dataset.depth, truth * 0.5));
  o.type = "sparse";
  o.sparse.mono = "torchscript";
  const PriorOutput sparse = make_depth_prior(o)->predict(in);
  CHECK_FALSE(sparse.floor_scaled);
  CHECK(((sparse.depth - truth * 0.5).abs() / (truth * 0.5)).mean().item<double>() < 0.02);
}

TEST_CASE("prior: reference_scale gives a monocular prior the frame's own scale, and needs its depth", "[prior]") {
  const auto dir = test::temp_dir("prior_reference");
  const int64_t H = 40, W = 60;
  const auto K = estimate_K(W, H, 60.0);
  const auto truth = 2.0f + torch::rand({H, W});
  PriorInput in;
  in.image = (truth / 20.0).unsqueeze(0).repeat({3, 1, 1});
  in.image[0][0][0] = 0.0f;  // a pixel the model leaves without depth: it stays invalid
  in.K = K;
  in.depth = truth;
  in.valid = torch::ones({H, W});
  in.valid[5][5] = 0.0f;  // the reference's invalid pixels take no part
  in.depth[5][5] = 1e6f;
  PriorOptions o;
  o.type = "torchscript";
  o.torchscript = save_module(dir, "third", "def forward(self, x):\n    return x[:, 0:1] * (20.0 / 3.0)\n");
  o.reference_scale = true;
  const PriorOutput out = make_depth_prior(o)->predict(in);
  CHECK(out.valid[0][0].item<float>() == 0.0f);
  CHECK(out.depth[0][0].item<float>() == 0.0f);
  const auto ok = (out.valid > 0) & (in.valid > 0);
  CHECK(((out.depth.masked_select(ok) - truth.masked_select(ok)).abs() / truth.masked_select(ok)).max().item<double>() <
        1e-4);
  in.depth = torch::Tensor();
  CHECK_THROWS_WITH(make_depth_prior(o)->predict(in), Catch::Contains("needs the frame's own depth"));
  o.camera_height_m = 1.6;
  CHECK_THROWS_WITH(config_from_json<PriorOptions>(config_to_json(o), "test"), Catch::Contains("camera_height_m"));
}

// The model end to end with the renderer: zero updates render like a direct lift of depth and colour,
// gradients reach the encoder through a rendered image, ablations run, and bad input is reported.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "core/config.h"
#include "decoder/composer.h"
#include "geometry/camera_torch.h"
#include "geometry/color.h"
#include "model/infinisplat.h"
#include "render/render.h"
#include "support/test_util.h"
#include "support/tiny_model.h"

using namespace isplat;

namespace {
constexpr int64_t H = 32, W = 48;

torch::Tensor scene_depth() {
  auto d = torch::full({H, W}, 3.0f);
  d.narrow(1, 10, 14).narrow(0, 8, 16).fill_(1.5f);  // a box in front of a wall
  return d;
}

Camera camera(double tx) {
  auto T = torch::eye(4);
  T[0][3] = tx;
  return {make_K(40, 40, W / 2.0, H / 2.0), T, W, H};
}
}  // namespace

TEST_CASE("model: zero updates render exactly like the directly lifted base Gaussians", "[model]") {
  torch::manual_seed(0);
  auto image = torch::rand({3, H, W});
  const Camera cam = camera(0.0);
  SamplerOptions so;
  so.budget = 3000;
  const Supports s = sample_supports(scene_depth(), torch::ones({H, W}), cam.K, image, so, 1);
  const BaseGaussians base = make_base_gaussians(s);
  const Gaussians composed = compose(base, torch::zeros({s.count(), kDeltaDim}), cam.K, cam.T_cw, ComposerOptions{});
  // Directly: back-project each support, isotropic sqrt(area), linear colour, opacity 0.5.
  Gaussians direct{backproject_points(s.uv, s.depth, cam.K),
                   torch::sqrt(s.area).unsqueeze(1).expand({-1, 3}).contiguous(),
                   torch::tensor({1.0f, 0.0f, 0.0f, 0.0f}).expand({s.count(), 4}).contiguous(),
                   srgb_to_linear(torch::clamp(s.color, 0.01, 0.99)), torch::full({s.count()}, 0.5f)};
  const Camera novel = camera(0.3);
  const auto a = render(composed, novel), b = render(direct, novel);
  CHECK(torch::allclose(a.rgb, b.rgb, 1e-4, 1e-5));
  CHECK(torch::allclose(a.depth, b.depth, 1e-4, 1e-4));
  CHECK(a.alpha.mean().item<float>() > 0.5f);
}

TEST_CASE("model: shapes, and gradients flow through the whole model into a rendered image", "[model]") {
  torch::manual_seed(1);
  InfiniSplat model(test::tiny_model_options());
  {
    torch::NoGradGuard g;  // a trained head: the zero-initialized one passes no gradient upstream
    model->decoder->head->weight.normal_(0, 0.1);
  }
  auto image = torch::rand({3, H, W});
  const Camera cam = camera(0.0);
  Prediction p = model->forward(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}), 3);
  CHECK(p.supports.count() == 600);
  CHECK(p.delta.sizes() == torch::IntArrayRef({600, 14}));
  CHECK(p.gaussians.means.sizes() == torch::IntArrayRef({600, 3}));
  CHECK(p.timings_ms.count("encoder") == 1);
  const auto out = render(p.gaussians, camera(0.2));
  CHECK(out.rgb.sizes() == torch::IntArrayRef({3, H, W}));
  (out.rgb.mean() + out.depth.mean()).backward();
  for (const char* name : {"encoder.vit.patch_embed.proj.weight", "encoder.cnn.stem.weight", "decoder.gate.weight",
                           "decoder.mlp.0.weight", "decoder.head.bias"}) {
    auto g = model->named_parameters()[name].grad();
    INFO(name);
    REQUIRE(g.defined());
    CHECK(torch::isfinite(g).all().item<bool>());
    CHECK(g.abs().sum().item<double>() > 0);
  }
  // predict() is deterministic and does not build a graph.
  const Prediction q1 = model->predict(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}), 3);
  const Prediction q2 = model->predict(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}), 3);
  CHECK_FALSE(q1.gaussians.means.requires_grad());
  CHECK(torch::equal(q1.gaussians.means, q2.gaussians.means));
}

TEST_CASE("model: every ablation switch builds and runs", "[model]") {
  auto image = torch::rand({3, H, W});
  const Camera cam = camera(0.0);
  struct Case {
    const char* name;
    std::function<void(ModelOptions&)> set;
  };
  const std::vector<Case> cases = {
      {"w/o learned updates", [](ModelOptions& o) { o.decoder.mode = "none"; }},
      {"w/o implicit decoder",
       [](ModelOptions& o) {
         o.decoder.mode = "dense";
         o.sampler.mode = "pixel";
       }},
      {"w/o DINO", [](ModelOptions& o) { o.encoder.dino = false; }},
      {"w/o CNN", [](ModelOptions& o) { o.encoder.cnn = false; }},
      {"pixel-aligned supports", [](ModelOptions& o) { o.sampler.mode = "pixel"; }},
      {"vertex + face supports", [](ModelOptions& o) { o.sampler.mode = "vertex_face"; }},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    ModelOptions o = test::tiny_model_options();
    c.set(o);
    InfiniSplat m(o);
    const Prediction p = m->predict(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}));
    CHECK(p.gaussians.count() > 0);
    CHECK(torch::isfinite(render(p.gaussians, camera(0.1)).rgb).all().item<bool>());
  }
}

TEST_CASE("model: the frozen SqueezeNet semantic branch builds and runs", "[model][weights]") {
  ISPLAT_REQUIRE_WEIGHTS();
  auto image = torch::rand({3, H, W});
  const Camera cam = camera(0.0);
  ModelOptions o = test::tiny_model_options();
  o.encoder.semantic = "squeeze";
  o.encoder.semantic_backbone = test::squeezenet_weights();
  InfiniSplat m(o);
  const Prediction p = m->predict(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}));
  CHECK(p.gaussians.count() > 0);
  CHECK(torch::isfinite(render(p.gaussians, camera(0.1)).rgb).all().item<bool>());
}

TEST_CASE("model: NaN depth holes are masked, all-invalid depth and tiny images are errors", "[model]") {
  InfiniSplat m(test::tiny_model_options());
  const Camera cam = camera(0.0);
  auto depth = scene_depth();
  depth.narrow(0, 0, 6).fill_(std::numeric_limits<float>::quiet_NaN());
  auto valid = torch::isfinite(depth).to(torch::kFloat32);
  const Prediction p = m->predict(torch::rand({3, H, W}), cam.K, cam.T_cw, depth, valid);
  CHECK(torch::isfinite(p.gaussians.means).all().item<bool>());
  CHECK((p.supports.uv.select(1, 1) >= 6.5f).all().item<bool>());  // nothing in the hole
  auto nan_depth = torch::full({H, W}, std::numeric_limits<float>::quiet_NaN());
  CHECK_THROWS_WITH(m->predict(torch::rand({3, H, W}), cam.K, cam.T_cw, nan_depth, torch::ones({H, W})),
                    Catch::Contains("no valid triangle"));
  const Camera small{make_K(10, 10, 5, 4), torch::eye(4), 10, 8};
  CHECK_THROWS_WITH(
      m->predict(torch::rand({3, 8, 10}), small.K, small.T_cw, torch::ones({8, 10}), torch::ones({8, 10})),
      Catch::Contains("smaller than one 16x16 ViT patch"));
}

TEST_CASE("model: the pipeline's after_prior hook changes the depth the model sees", "[model]") {
  ModelOptions o = test::tiny_model_options();
  o.prior.type = "dataset";
  Pipeline pipe(o);
  pipe.model()->eval();
  const Camera cam = camera(0.0);
  torch::NoGradGuard no_grad;
  const PriorInput in{torch::rand({3, H, W}), cam.K, scene_depth(), torch::ones({H, W}), torch::Tensor(), 1};
  const Prediction plain = pipe.run(in, cam.T_cw, false);
  const Prediction scaled =
      pipe.run(in, cam.T_cw, false, [](PriorOutput& p) { p.depth = p.depth * 2; });  // e.g. a scale error
  REQUIRE(plain.supports.depth.numel() == scaled.supports.depth.numel());
  CHECK(torch::allclose(scaled.supports.depth, plain.supports.depth * 2, 1e-4, 1e-5));
}

TEST_CASE(
    "model: the defaults put a support on every valid pixel and hidden surface behind silhouettes, decoded by "
    "the dense head",
    "[model]") {
  torch::manual_seed(2);
  const ModelOptions o = test::tiny_default_options();
  REQUIRE(o.sampler.mode == "pixel");
  REQUIRE(o.decoder.mode == "dense");
  InfiniSplat model(o);
  REQUIRE(model->dense);
  CHECK_FALSE(model->decoder);
  {
    torch::NoGradGuard g;  // a trained head: the zero-initialized one passes no gradient upstream
    model->dense->out->weight.normal_(0, 0.1);
  }
  auto image = torch::rand({3, H, W});
  const Camera cam = camera(0.0);
  Prediction p = model->forward(image, cam.K, cam.T_cw, scene_depth(), torch::ones({H, W}), 3);
  CHECK(p.supports.count() == H * W + p.supports.behind);  // one per pixel, plus the box's hidden wall
  CHECK(p.supports.behind > 0);
  CHECK(p.delta.abs().sum().item<double>() > 0);
  render(p.gaussians, camera(0.2)).rgb.mean().backward();
  for (const char* name :
       {"encoder.vit.patch_embed.proj.weight", "encoder.cnn.stem.weight", "dense.reduce.weight", "dense.out.bias"}) {
    auto g = model->named_parameters()[name].grad();
    INFO(name);
    REQUIRE(g.defined());
    CHECK(g.abs().sum().item<double>() > 0);
  }
}

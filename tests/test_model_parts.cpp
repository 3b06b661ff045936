// Encoder, decoder and composer: shapes, the DINOv3 checkpoint names, grid_sample conventions at pixel
// centres and corners, zero updates reproducing the base Gaussians, and bad input.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "decoder/composer.h"
#include "decoder/dense_head.h"
#include "decoder/feature_sampler.h"
#include "decoder/implicit_decoder.h"
#include "encoder/dual_encoder.h"
#include "geometry/camera_torch.h"
#include "geometry/color.h"
#include "geometry/convert.h"
#include "io/safetensors.h"
#include "nets/feature_net.h"
#include "nets/imagenet.h"
#include "support/test_util.h"

using namespace isplat;

namespace {
ViTOptions tiny_vit() {
  ViTOptions v;
  v.size = "custom";
  v.embed_dim = 32;
  v.depth = 2;
  v.heads = 2;
  return v;
}
}  // namespace

TEST_CASE("encoder: ViT and CNN give feature maps at 1/16 and 1/4", "[encoder]") {
  EncoderOptions o;
  o.vit = tiny_vit();
  o.cnn_options.width = 8;
  DualEncoder enc(o);
  auto f = enc->forward(torch::rand({2, 3, 64, 96}));
  CHECK(f.dino.sizes() == torch::IntArrayRef({2, 32, 4, 6}));
  CHECK(f.cnn.sizes() == torch::IntArrayRef({2, 128, 16, 24}));
  auto g = enc->forward(torch::rand({1, 3, 50, 70}));  // resized to 48x64
  CHECK(g.dino.sizes() == torch::IntArrayRef({1, 32, 3, 4}));
  CHECK_THROWS_WITH(enc->forward(torch::rand({1, 3, 12, 40})), Catch::Contains("smaller than one 16x16 ViT patch"));
  o.dino = false;
  DualEncoder cnn_only(o);
  CHECK_FALSE(cnn_only->forward(torch::rand({1, 3, 32, 32})).dino.defined());
  o.cnn = false;
  CHECK_THROWS_WITH(DualEncoder(o), Catch::Contains("cannot both be false"));
}

TEST_CASE("encoder: the frozen SqueezeNet semantic branch gives maps at 1/16 of the ViT's width", "[encoder]") {
  ISPLAT_REQUIRE_WEIGHTS();
  EncoderOptions o;
  o.vit = tiny_vit();
  o.semantic = "squeeze";
  o.semantic_backbone = test::squeezenet_weights();
  o.cnn_options.width = 8;
  DualEncoder enc(o);
  CHECK_FALSE(enc->vit);
  CHECK(enc->dino_dim() == 32);  // projected to encoder.vit's width: the decoder costs the same
  auto image = torch::rand({1, 3, 192, 256}, torch::requires_grad());
  auto f = enc->forward(image);
  // Valid convolutions and ceil-mode pooling: 11 x 15 cells cover the 12 x 16 patch grid's extent.
  CHECK(f.dino.sizes() == torch::IntArrayRef({1, 32, 11, 15}));
  // Gradients reach the projection but not the frozen backbone or the image through it.
  f.dino.sum().backward();
  CHECK(enc->squeeze_proj->weight.grad().abs().sum().item<float>() > 0);
  CHECK_FALSE(image.grad().defined());
  // Only the projection and the CNN branch train: the backbone's weights are not module parameters.
  for (const auto& p : enc->named_parameters())
    CHECK((p.key().rfind("cnn.", 0) == 0 || p.key().rfind("squeeze_proj.", 0) == 0));
  // The projection's input: the backbone's fire9 map scaled to unit length times sqrt(512) (unit RMS per cell).
  const FeatureNet reference_net("squeezenet1_1", {12}, o.semantic_backbone);
  const auto unit = normalize_channels(reference_net.forward(imagenet_normalize(image.detach()))[0]) * std::sqrt(512.0);
  CHECK(unit.pow(2).mean(1).sqrt().sub(1).abs().max().item<float>() < 1e-4f);
  const auto expected = torch::conv2d(unit, enc->squeeze_proj->weight, enc->squeeze_proj->bias);
  CHECK(torch::allclose(f.dino.detach(), expected, 1e-4, 1e-5));
  // A missing backbone file fails, naming it.
  o.semantic_backbone = "no/such/squeeze.safetensors";
  CHECK_THROWS_WITH(DualEncoder(o), Catch::Contains("no/such/squeeze.safetensors"));
}

TEST_CASE("encoder: inference attention in row blocks equals the one-shot softmax attention", "[encoder]") {
  torch::manual_seed(4);
  Attention whole(32, 2, 1 << 20);
  const auto x = torch::randn({4, 300, 32});
  const auto sin = torch::randn({296, 16}), cos = torch::randn({296, 16});
  torch::Tensor with_grad = whole->forward(x, sin, cos);  // the autograd path: one softmax
  torch::NoGradGuard no_grad;
  // 1 MB holds 109 query rows of 4 x 2 heads x 300 keys: three blocks. A huge budget gives one block.
  Attention tiny(32, 2, 1);
  for (const auto& item : whole->named_parameters()) tiny->named_parameters()[item.key()].copy_(item.value());
  for (const auto& item : whole->named_buffers()) tiny->named_buffers()[item.key()].copy_(item.value());
  CHECK(torch::allclose(tiny->forward(x, sin, cos), with_grad, 1e-5, 1e-6));
  CHECK(torch::allclose(whole->forward(x, sin, cos), with_grad, 1e-5, 1e-6));
}

TEST_CASE("encoder: parameters carry the official DINOv3 names and a checkpoint loads", "[encoder]") {
  DinoViT a(tiny_vit()), b(tiny_vit());
  std::map<std::string, torch::Tensor> state;
  for (const auto& p : a->named_parameters(true)) state[p.key()] = p.value().detach().clone();
  for (const auto& p : a->named_buffers(true)) state[p.key()] = p.value().detach().clone();
  for (const char* name : {"cls_token", "storage_tokens", "mask_token", "patch_embed.proj.weight", "rope_embed.periods",
                           "blocks.0.norm1.weight", "blocks.0.attn.qkv.weight", "blocks.0.attn.qkv.bias",
                           "blocks.0.attn.qkv.bias_mask", "blocks.0.attn.proj.weight", "blocks.0.ls1.gamma",
                           "blocks.1.mlp.fc1.weight", "blocks.1.mlp.fc2.bias", "blocks.1.ls2.gamma", "norm.bias"})
    CHECK(state.count(name) == 1);
  CHECK(state.at("storage_tokens").sizes() == torch::IntArrayRef({1, 4, 32}));
  CHECK(state.at("rope_embed.periods").sizes() == torch::IntArrayRef({4}));  // head dim 16 / 4
  CHECK(state.at("blocks.0.attn.qkv.bias_mask").narrow(0, 32, 32).abs().sum().item<float>() == 0.0f);  // K bias masked
  const auto dir = test::temp_dir("dinov3");
  state["local_cls_norm.weight"] = torch::ones({32});  // present in some official checkpoints; ignored
  write_safetensors(dir + "/vit.safetensors", state);
  auto x = torch::rand({1, 3, 32, 48});
  CHECK_FALSE(torch::allclose(a->forward(x), b->forward(x)));
  load_dinov3_safetensors(b, dir + "/vit.safetensors");
  CHECK(torch::allclose(a->forward(x), b->forward(x)));

  state.erase("norm.bias");
  state["blocks.7.attn.qkv.weight"] = torch::zeros({96, 32});
  state["blocks.0.ls1.gamma"] = torch::zeros({31});
  write_safetensors(dir + "/bad.safetensors", state);
  const std::string msg = test::error_of([&] { load_dinov3_safetensors(b, dir + "/bad.safetensors"); });
  CHECK_THAT(msg, Catch::Contains("missing keys: norm.bias"));
  CHECK_THAT(msg, Catch::Contains("unexpected keys: blocks.7.attn.qkv.weight"));
  CHECK_THAT(msg, Catch::Contains("shape or type mismatches: blocks.0.ls1.gamma (file [31], model [32])"));
}

TEST_CASE("decoder: grid_sample query matches hand-computed bilinear values", "[decoder]") {
  // A 4x4 map over a 16x16 image: texel (i, j) covers pixels [4j, 4j+4) x [4i, 4i+4), centre at 4j+2.
  auto f = torch::arange(16, torch::kFloat32).view({1, 1, 4, 4});
  auto uv = torch::tensor({{2.0f, 2.0f},    // centre of texel (0,0)
                           {10.0f, 6.0f},   // centre of texel (1,2)
                           {4.0f, 2.0f},    // halfway between texels (0,0) and (0,1)
                           {0.0f, 0.0f},    // image corner: clamped to the border texel
                           {16.0f, 16.0f},  // opposite corner
                           {4.0f, 4.0f}});  // centre of texels (0,0),(0,1),(1,0),(1,1)
  auto q = query_features(f, uv, 16, 16).squeeze(1);
  CHECK(q[0].item<float>() == Approx(0.0f));
  CHECK(q[1].item<float>() == Approx(6.0f));
  CHECK(q[2].item<float>() == Approx(0.5f));
  CHECK(q[3].item<float>() == Approx(0.0f).margin(1e-5));
  CHECK(q[4].item<float>() == Approx(15.0f).margin(1e-4));
  CHECK(q[5].item<float>() == Approx(2.5f));
}

TEST_CASE("decoder: zero-initialized head and gated fusion shapes", "[decoder]") {
  DecoderOptions o;
  o.chunk = 7;  // several chunks
  ImplicitDecoder d(o, 32, 128);
  EncoderFeatures f{torch::rand({1, 32, 3, 4}), torch::rand({1, 128, 12, 16})};
  auto uv = torch::rand({20, 2}) * 48;
  auto delta = d->forward(uv, 64, 48, f);
  CHECK(delta.sizes() == torch::IntArrayRef({20, 14}));
  CHECK(delta.abs().max().item<float>() == 0.0f);  // step 0 renders the base Gaussians
  // The texel-level fast path equals decoding features sampled at each support.
  {
    torch::NoGradGuard g;
    d->head->weight.normal_(0, 0.1);
    d->head->bias.normal_(0, 0.1);
    auto fast = d->forward(uv, 64, 48, f);
    auto direct = d->decode_features(query_features(f.dino, uv, 64, 48), query_features(f.cnn, uv, 64, 48));
    CHECK(torch::allclose(fast, direct, 1e-4, 1e-5));
    CHECK(fast.abs().max().item<float>() > 0.0f);
  }
  CHECK(d->mlp->size() == 3);
  ImplicitDecoder cnn_only(o, 0, 128);
  CHECK(cnn_only->forward(uv, 64, 48, EncoderFeatures{torch::Tensor(), f.cnn}).sizes() == torch::IntArrayRef({20, 14}));
  DenseHead dense(32, 128);
  auto map = dense->forward(f, 64, 48);
  CHECK(map.sizes() == torch::IntArrayRef({1, 14, 48, 64}));
}

TEST_CASE("composer: zero updates reproduce the base Gaussians exactly", "[composer]") {
  BaseGaussians b;
  b.uv = torch::tensor({{10.5f, 20.5f}, {30.0f, 5.25f}});
  b.depth_factor = 0.5;  // min depth 2 m
  b.z_n = torch::tensor({1.0f, 2.5f});
  b.scale_n = torch::tensor({0.01f, 0.02f});
  b.color = torch::tensor({{0.2f, 0.5f, 0.9f}, {0.01f, 0.99f, 0.5f}});
  b.opacity = torch::full({2}, 0.5f);
  auto K = make_K(50, 55, 32, 24, torch::kFloat64);
  ComposerOptions o;
  auto g = compose_camera(b, torch::zeros({2, 14}, torch::kFloat64), K, o);
  auto z = torch::tensor({2.0, 5.0}, torch::kFloat64);
  auto expect_means = backproject_points(b.uv.to(torch::kFloat64), z, K);
  CHECK(torch::allclose(g.means, expect_means, 1e-9, 1e-12));
  auto expect_scales = (b.scale_n.to(torch::kFloat64) / b.depth_factor).unsqueeze(1).expand({2, 3});
  CHECK(torch::allclose(g.scales, expect_scales, 1e-9, 1e-12));
  CHECK(torch::allclose(g.quats, torch::tensor({{1.0, 0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}}, torch::kFloat64)));
  CHECK(torch::allclose(g.colors, srgb_to_linear(torch::clamp(b.color.to(torch::kFloat64), 0.01, 0.99)), 1e-9, 1e-12));
  CHECK(torch::allclose(g.opacities, torch::full({2}, 0.5, torch::kFloat64)));
  // Scale multiplier: 1 with slope 1 at ds = 0, bounded by [0, 4].
  auto d = torch::zeros({2, 14}, torch::kFloat64);
  d.select(1, 3).fill_(1e-4);
  auto g2 = compose_camera(b, d, K, o);
  CHECK((g2.scales.select(1, 0) / g.scales.select(1, 0) - 1.0)[0].item<double>() == Approx(1e-4).epsilon(1e-3));
  d.select(1, 3).fill_(1e3);
  CHECK((compose_camera(b, d, K, o).scales.select(1, 0) / g.scales.select(1, 0))[0].item<double>() == Approx(4.0));
  // Depth stays positive however large dz is.
  d.zero_();
  d.select(1, 2).fill_(-1e6);
  CHECK((compose_camera(b, d, K, o).means.select(1, 2) > 0).all().item<bool>());
  CHECK(inverse_softplus(torch::tensor({100.0})).item<double>() == Approx(100.0));
  // Opacity: the clamp to [0.01, 0.99] cuts the gradient; unclamped_opacity is the same value inside the range and
  // keeps it outside.
  d.zero_();
  d.select(1, 13).copy_(torch::tensor({0.3, 8.0}, torch::kFloat64));
  const auto composed = compose_camera(b, d, K, o).opacities, free = unclamped_opacity(d);
  CHECK(free[0].item<double>() == Approx(1.0 / (1.0 + std::exp(-0.3))));
  CHECK(composed[0].item<double>() == Approx(free[0].item<double>()));
  CHECK(composed[1].item<double>() == Approx(0.99));
  CHECK(free[1].item<double>() == Approx(1.0 / (1.0 + std::exp(-8.0))));
  auto da = d.clone().requires_grad_(true);
  compose_camera(b, da, K, o).opacities[1].backward();
  CHECK(da.grad()[1][13].item<double>() == 0.0);
  auto da2 = d.clone().requires_grad_(true);
  unclamped_opacity(da2)[1].backward();
  CHECK(da2.grad()[1][13].item<double>() > 0.0);
}

TEST_CASE("composer: scale_floor_px widens Gaussians narrower than a share of a source pixel", "[composer]") {
  BaseGaussians b;
  b.uv = torch::tensor({{10.5f, 20.5f}, {30.0f, 5.25f}});
  b.depth_factor = 0.5;                      // metres = normalized / 0.5
  b.z_n = torch::tensor({1.0f, 2.5f});       // 2 m and 5 m
  b.scale_n = torch::tensor({1e-4f, 0.5f});  // 0.2 mm: far below a pixel at 2 m; 1 m: far above one at 5 m
  b.color = torch::full({2, 3}, 0.5f);
  b.opacity = torch::full({2}, 0.5f);
  const auto K = make_K(50, 50, 32, 24, torch::kFloat64);
  const auto d = torch::zeros({2, 14}, torch::kFloat64);
  ComposerOptions o;
  const Gaussians plain = compose_camera(b, d, K, o);
  o.scale_floor_px = 0.5;
  const Gaussians floored = compose_camera(b, d, K, o);
  // The tiny one becomes half a pixel wide at its depth (0.5 * 2 m / 50 = 2 cm) on every axis; the large one barely
  // changes (sqrt(1 + 0.05^2)); opacities, means and rotations stay.
  const double floor0 = 0.5 * 2.0 / 50.0, s0 = 2e-4;
  for (int64_t axis = 0; axis < 3; ++axis) {
    CHECK(floored.scales[0][axis].item<double>() == Approx(std::hypot(s0, floor0)).epsilon(1e-5));
    CHECK(floored.scales[1][axis].item<double>() == Approx(std::hypot(1.0, 0.05)).epsilon(1e-5));
  }
  CHECK(torch::equal(floored.opacities, plain.opacities));
  CHECK(torch::equal(floored.means, plain.means));
  CHECK(torch::equal(floored.quats, plain.quats));
  // Finite gradients reach the scale updates even where the multiplier saturates at 0 (the floor alone is left).
  o.scale_min = 0.0;
  auto da = d.clone();
  da.select(1, 3).fill_(-1e3);
  da.requires_grad_(true);
  compose_camera(b, da, K, o).scales.sum().backward();
  CHECK(torch::isfinite(da.grad()).all().item<bool>());
  // 0 is off: exactly the unfloored Gaussians.
  CHECK(torch::equal(compose_camera(b, d, K, ComposerOptions{}).scales, plain.scales));
}

TEST_CASE("composer: orientation = surface turns each Gaussian's local z onto its support's normal", "[composer]") {
  BaseGaussians b;
  b.uv = torch::tensor({{10.5f, 20.5f}, {30.0f, 5.25f}, {3.0f, 4.0f}});
  b.depth_factor = 0.5;
  b.z_n = torch::tensor({1.0f, 2.5f, 1.5f});
  b.scale_n = torch::full({3}, 0.01f);
  b.color = torch::full({3, 3}, 0.5f);
  b.opacity = torch::full({3}, 0.5f);
  const double l = std::sqrt(0.09 + 0.04 + 1.0);
  b.normal =
      torch::tensor({{0.0f, 0.0f, -1.0f}, {0.3f / float(l), -0.2f / float(l), -1.0f / float(l)}, {-0.8f, 0.0f, -0.6f}});
  auto K = make_K(50, 55, 32, 24, torch::kFloat64);
  ComposerOptions o;
  o.orientation = "surface";
  auto d = torch::zeros({3, 14}, torch::kFloat64);
  const Gaussians g = compose_camera(b, d, K, o);
  // A camera-facing surface keeps the identity; every local z axis lands on the normal's line, pointing away from
  // the camera.
  CHECK(torch::allclose(g.quats[0], torch::tensor({1.0, 0.0, 0.0, 0.0}, torch::kFloat64)));
  for (int64_t k = 0; k < 3; ++k) {
    auto q = g.quats[k];
    const Eigen::Matrix3d R = rotation_from_quaternion(
        Eigen::Vector4d(q[0].item<double>(), q[1].item<double>(), q[2].item<double>(), q[3].item<double>()));
    const Eigen::Vector3d n(b.normal[k][0].item<double>(), b.normal[k][1].item<double>(),
                            b.normal[k][2].item<double>());
    CHECK((R.col(2) + n).norm() < 1e-6);
  }
  // The update dq acts in that frame: q = q_surface * (1 + dq).
  d.select(1, 7).fill_(0.2);
  ComposerOptions camera;
  const auto rotated = compose_camera(b, d, K, o).quats, local = compose_camera(b, d, K, camera).quats;
  CHECK(torch::allclose(local, torch::tensor({1.0, 0.2, 0.0, 0.0}, torch::kFloat64).expand({3, 4})));
  CHECK(torch::allclose(rotated[0], local[0]));
  CHECK_FALSE(torch::allclose(rotated[1], local[1]));
  // Without normals the option is a clear error.
  b.normal = torch::Tensor();
  CHECK_THROWS_WITH(compose_camera(b, d, K, o), Catch::Contains("orientation = surface"));
}

TEST_CASE("composer: world transform moves means and rotates quaternions", "[composer]") {
  Gaussians g{torch::tensor({{0.0, 0.0, 2.0}}), torch::ones({1, 3}) * 0.1, torch::tensor({{1.0, 0.0, 0.0, 0.0}}),
              torch::full({1, 3}, 0.5), torch::full({1}, 0.5)};
  // Camera at world (1, 0, 0) rotated 90 degrees about y.
  auto T_cw = torch::eye(4, torch::kFloat64);
  T_cw.narrow(0, 0, 3).narrow(1, 0, 3).copy_(
      torch::tensor({0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0}, torch::kFloat64).view({3, 3}));
  T_cw.narrow(0, 0, 3).select(1, 3).copy_(
      -torch::matmul(T_cw.narrow(0, 0, 3).narrow(1, 0, 3), torch::tensor({1.0, 0.0, 0.0}, torch::kFloat64)));
  auto w = camera_to_world(g.to(torch::kFloat64), T_cw);
  auto back = transform_points(T_cw, w.means);
  CHECK(torch::allclose(back, g.means.to(torch::kFloat64), 1e-9, 1e-12));
  CHECK(std::abs(w.quats[0][0].item<double>()) == Approx(std::sqrt(0.5)));
}

TEST_CASE("decoder: the fast feature sampler equals grid_sample, with exact gradients", "[decoder]") {
  torch::manual_seed(2);
  auto f = torch::randn({1, 5, 6, 7}, torch::kFloat64).requires_grad_(true);
  auto uv =
      torch::rand({300, 2}, torch::kFloat64) * torch::tensor({70.0, 60.0}, torch::kFloat64) - 2.0;  // some outside
  uv[0][0] = 0.0;
  uv[1][1] = 60.0;
  auto ours = sample_features(f, uv, 70, 60), ref = query_features(f, uv, 70, 60);
  CHECK(torch::allclose(ours, ref, 1e-12, 1e-12));
  auto w = torch::randn_like(ours);
  auto g1 = torch::autograd::grad({(ours * w).sum()}, {f})[0];
  auto g2 = torch::autograd::grad({(ref * w).sum()}, {f})[0];
  CHECK(torch::allclose(g1, g2, 1e-12, 1e-12));
  CHECK(torch::equal(sample_features(f.detach().to(torch::kFloat32), uv, 70, 60),
                     sample_features(f.detach().to(torch::kFloat32), uv, 70, 60)));
}

TEST_CASE("decoder: the fused gated query equals the unfused ops, values and gradients", "[decoder]") {
  torch::manual_seed(5);
  auto opts = torch::TensorOptions().dtype(torch::kFloat64).requires_grad(true);
  auto d = torch::randn({1, 6, 3, 4}, opts), gd = torch::randn({1, 6, 3, 4}, opts);
  auto cp = torch::randn({1, 6, 12, 16}, opts), gc = torch::randn({1, 6, 12, 16}, opts);
  auto uv = torch::rand({200, 2}, torch::kFloat64) * torch::tensor({64.0, 48.0}, torch::kFloat64);
  auto fused = gated_sample(d, gd, cp, gc, uv, 64, 48);
  auto g = torch::sigmoid(query_features(gd, uv, 64, 48) + query_features(gc, uv, 64, 48));
  auto ref = g * query_features(d, uv, 64, 48) + (1 - g) * query_features(cp, uv, 64, 48);
  CHECK(torch::allclose(fused, ref, 1e-12, 1e-12));
  auto w = torch::randn_like(ref);
  auto ga = torch::autograd::grad({(fused * w).sum()}, {d, gd, cp, gc});
  auto gb = torch::autograd::grad({(ref * w).sum()}, {d, gd, cp, gc});
  for (int k = 0; k < 4; ++k) CHECK(torch::allclose(ga[k], gb[k], 1e-10, 1e-12));
  // Float: the gate goes through exp2_poly instead of std::exp, within float rounding of the double result, with
  // gates driven to saturation (|s| up to 200) included.
  {
    torch::NoGradGuard no_grad;
    const auto f32 = [](const torch::Tensor& t) { return t.detach().to(torch::kFloat32); };
    const auto big = torch::randn({1, 6, 3, 4}, torch::kFloat64) * 60.0;
    const auto fused32 = gated_sample(f32(d), f32(big), f32(cp), f32(gc), f32(uv), 64, 48);
    const auto g64 = torch::sigmoid(query_features(big, uv, 64, 48) + query_features(gc.detach(), uv, 64, 48));
    const auto ref64 =
        g64 * query_features(d.detach(), uv, 64, 48) + (1 - g64) * query_features(cp.detach(), uv, 64, 48);
    CHECK(torch::allclose(fused32.to(torch::kFloat64), ref64, 1e-5, 1e-5));
    CHECK((g64 > 0.999).sum().item<int64_t>() > 0);
    CHECK((g64 < 0.001).sum().item<int64_t>() > 0);
  }
  CHECK_THROWS_WITH(gated_sample(d, gd, cp.narrow(1, 0, 5), gc.narrow(1, 0, 5), uv, 64, 48),
                    Catch::Contains("dino's C"));
}

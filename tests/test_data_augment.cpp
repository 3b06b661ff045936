// Tuple augmentation: determinism, a consistent mirror, zoom with its intrinsics, and one shared colour jitter.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <cmath>

#include "data/augment.h"
#include "data/hypersim.h"
#include "data/tuples.h"
#include "geometry/camera_torch.h"
#include "support/tiny_dataset.h"

using namespace isplat;

namespace {
constexpr int64_t kW = 40, kH = 30;

// A pose with a rotation (about y, then x) and a translation.
torch::Tensor pose(double yaw, double pitch, double tx) {
  const double cy = std::cos(yaw), sy = std::sin(yaw), cx = std::cos(pitch), sx = std::sin(pitch);
  return torch::tensor(
      {{cy, sy * sx, sy * cx, tx}, {0.0, cx, -sx, 0.1}, {-sy, cy * sx, cy * cx, 0.05}, {0.0, 0.0, 0.0, 1.0}},
      torch::kFloat32);
}

// A view whose image encodes each pixel's ray: R = 0.5 + x/z / 2, G = 0.5 + y/z / 2 (linear in the pixel), with
// depth on a slanted plane and an invalid block (depth 0, valid 0).
ViewTensors ray_view(double yaw, double tx, const std::string& name) {
  ViewTensors v;
  v.camera.K = make_K(30.0, 28.0, 19.0, 16.0);
  v.camera.T_cw = pose(yaw, -0.5 * yaw, tx);
  v.camera.width = kW, v.camera.height = kH;
  const auto uv = pixel_centers(kH, kW);
  const auto x = (uv.select(2, 0) - 19.0) / 30.0, y = (uv.select(2, 1) - 16.0) / 28.0;
  v.image = torch::stack({0.5 + x / 2, 0.5 + y / 2, torch::full({kH, kW}, 0.25)});
  v.valid = torch::ones({kH, kW});
  v.valid.slice(0, 11, 17).slice(1, 15, 23).zero_();  // central: every zoom window keeps part of it
  v.depth = (2.0 + 0.05 * uv.select(2, 0) + 0.02 * uv.select(2, 1)) * v.valid;
  v.name = name;
  return v;
}

TupleSample ray_tuple() {
  TupleSample s;
  s.context = ray_view(0.0, 0.0, "ctx");
  s.targets = {ray_view(0.15, 0.3, "t0"), ray_view(-0.1, -0.2, "t1")};
  s.targets[1].camera.K[0][1] = 0.4;  // a skewed camera: the mirror must flip the skew's sign
  s.baselines = {0.3, 0.2};
  s.overlaps = {0.9, 0.9};
  return s;
}

bool same_view(const ViewTensors& a, const ViewTensors& b) {
  return torch::equal(a.image, b.image) && torch::equal(a.depth, b.depth) && torch::equal(a.valid, b.valid) &&
         torch::allclose(a.camera.K, b.camera.K) && torch::allclose(a.camera.T_cw, b.camera.T_cw);
}

bool same_tuple(const TupleSample& a, const TupleSample& b) {
  if (!same_view(a.context, b.context) || a.targets.size() != b.targets.size()) return false;
  for (size_t i = 0; i < a.targets.size(); ++i)
    if (!same_view(a.targets[i], b.targets[i])) return false;
  return true;
}

// Where the context pixel (u, v) at its depth lands in `target`.
torch::Tensor reproject(const TupleSample& s, const ViewTensors& target, double u, double v, double depth) {
  const auto uv = torch::tensor({{u, v}}, torch::kFloat32);
  const auto pc = backproject_points(uv, torch::tensor({depth}, torch::kFloat32), s.context.camera.K);
  const auto pw = transform_points(invert_poses(s.context.camera.T_cw), pc);
  return project_points(transform_points(target.camera.T_cw, pw), target.camera.K)[0];
}

AugmentOptions all_on() {
  AugmentOptions o;
  o.flip = 0.5, o.zoom = 0.3, o.brightness = 0.3, o.contrast = 0.3, o.saturation = 0.5, o.gamma = 0.3;
  o.channel_shuffle = 0.5, o.gray = 0.2;
  return o;
}
}  // namespace

TEST_CASE("augment: all-zero options change nothing, and a seed fixes the result", "[data][augment]") {
  auto s = ray_tuple();
  augment_tuple(s, AugmentOptions{}, 5);
  CHECK(same_tuple(s, ray_tuple()));

  auto a = ray_tuple(), b = ray_tuple();
  augment_tuple(a, all_on(), 11);
  augment_tuple(b, all_on(), 11);
  CHECK(same_tuple(a, b));
  CHECK_FALSE(same_tuple(a, ray_tuple()));
  bool seed_matters = false;
  for (uint64_t seed = 12; seed < 20 && !seed_matters; ++seed) {
    auto c = ray_tuple();
    augment_tuple(c, all_on(), seed);
    seed_matters = !same_tuple(a, c);
  }
  CHECK(seed_matters);
  for (const auto* v : {&a.context, &a.targets[0], &a.targets[1]}) {
    CHECK(v->image.min().item<float>() >= 0.0f);
    CHECK(v->image.max().item<float>() <= 1.0f);
    CHECK(v->image.sizes() == torch::IntArrayRef({3, kH, kW}));
    CHECK(((v->depth > 0) == (v->valid > 0.5)).all().item<bool>());
  }
}

TEST_CASE("augment: the mirror keeps every view of the tuple consistent", "[data][augment]") {
  AugmentOptions o;
  o.flip = 1.0;
  auto m = ray_tuple();
  augment_tuple(m, o, 3);
  const auto s = ray_tuple();
  CHECK(torch::equal(m.context.image, s.context.image.flip({2})));
  CHECK(torch::equal(m.context.depth, s.context.depth.flip({1})));
  CHECK(torch::equal(m.context.valid, s.context.valid.flip({1})));
  CHECK(torch::equal(m.targets[1].valid, s.targets[1].valid.flip({1})));
  CHECK(m.targets[1].camera.K[0][1].item<float>() == Approx(-0.4f));
  // A context pixel and its mirror image land on mirrored pixels of every target, at the same depth.
  for (size_t t = 0; t < s.targets.size(); ++t) {
    const auto before = reproject(s, s.targets[t], 7.5, 11.5, 2.5);
    const auto after = reproject(m, m.targets[t], kW - 7.5, 11.5, 2.5);
    CHECK(after[0].item<float>() == Approx(kW - before[0].item<float>()).margin(1e-4));
    CHECK(after[1].item<float>() == Approx(before[1].item<float>()).margin(1e-4));
  }
  CHECK(torch::det(m.context.camera.T_cw.slice(0, 0, 3).slice(1, 0, 3)).item<float>() == Approx(1.0f));
  augment_tuple(m, o, 3);  // mirroring twice restores the tuple
  CHECK(same_tuple(m, ray_tuple()));
}

TEST_CASE("augment: zoom scales the focal length and keeps each pixel on its ray", "[data][augment]") {
  AugmentOptions o;
  o.zoom = 0.5;
  const auto K0 = ray_tuple().context.camera.K;
  const double fx0 = K0[0][0].item<double>(), fy0 = K0[1][1].item<double>();
  const double cx0 = K0[0][2].item<double>(), cy0 = K0[1][2].item<double>();
  bool zoomed = false;
  for (uint64_t seed = 0; seed < 6; ++seed) {
    auto z = ray_tuple();
    // Depth along one image axis per view, so each depth reads back the source pixel's column or row.
    const auto uv = pixel_centers(kH, kW);
    z.context.depth = (2.0 + 0.05 * uv.select(2, 0)) * z.context.valid;
    z.targets[0].depth = (2.0 + 0.05 * uv.select(2, 1)) * z.targets[0].valid;
    augment_tuple(z, o, seed);
    for (int view = 0; view < 2; ++view) {
      const ViewTensors& v = view == 0 ? z.context : z.targets[0];
      const auto K = v.camera.K.to(torch::kFloat64);
      const double sx = K[0][0].item<double>() / fx0, sy = K[1][1].item<double>() / fy0;
      CHECK(sx >= 1.0);
      CHECK(sx <= 1.5 * 1.05);  // the window is rounded to whole pixels
      zoomed = zoomed || sx > 1.05;
      // The image encodes each pixel's ray through the original K; read back, it must be the new K's ray.
      const auto uvd = uv.to(torch::kFloat64);
      const auto x = (uvd.select(2, 0) - K[0][2]) / K[0][0], y = (uvd.select(2, 1) - K[1][2]) / K[1][1];
      const auto in = torch::indexing::Slice(2, -2);
      CHECK(torch::allclose(((v.image[0] - 0.5) * 2).to(torch::kFloat64).index({in, in}), x.index({in, in}), 0, 2e-3));
      CHECK(torch::allclose(((v.image[1] - 0.5) * 2).to(torch::kFloat64).index({in, in}), y.index({in, in}), 0, 2e-3));
      // Each valid pixel's depth comes from the source pixel whose centre is nearest where its own centre maps.
      const double x0 = cx0 - K[0][2].item<double>() / sx, y0 = cy0 - K[1][2].item<double>() / sy;
      const auto source = view == 0 ? x0 + uvd.select(2, 0) / sx : y0 + uvd.select(2, 1) / sy;
      const auto read = (v.depth.to(torch::kFloat64) - 2.0) / 0.05;  // the source pixel's centre coordinate
      const auto ok = v.valid > 0.5;
      CHECK(((read - source).abs().masked_select(ok).max().item<double>() <= 0.5 + 1e-3));
      CHECK(((v.depth > 0) == ok).all().item<bool>());
      CHECK(ok.logical_not().any().item<bool>());  // the invalid block survives (as invalid, not as depth)
    }
  }
  CHECK(zoomed);
}

TEST_CASE("augment: one photometric jitter is shared by every view", "[data][augment]") {
  AugmentOptions o;
  o.brightness = 0.4, o.contrast = 0.3, o.saturation = 0.5, o.gamma = 0.3, o.channel_shuffle = 1.0;
  auto s = ray_tuple();
  augment_tuple(s, o, 21);
  CHECK(torch::equal(s.context.image, s.targets[0].image));  // identical pictures stay identical
  CHECK_FALSE(torch::equal(s.context.image, ray_tuple().context.image));
  CHECK(torch::equal(s.context.depth, ray_tuple().context.depth));  // geometry untouched

  AugmentOptions gray;
  gray.gray = 1.0;
  auto g = ray_tuple();
  augment_tuple(g, gray, 1);
  CHECK(torch::equal(g.context.image[0], g.context.image[1]));
  CHECK(torch::equal(g.context.image[1], g.context.image[2]));

  AugmentOptions gain;
  gain.brightness = 0.25;
  for (uint64_t seed = 0; seed < 8; ++seed) {
    auto b = ray_tuple();
    augment_tuple(b, gain, seed);
    const auto ratio = b.context.image[2] / ray_tuple().context.image[2];  // blue is 0.25: never clipped
    CHECK(ratio.max().item<float>() - ratio.min().item<float>() < 1e-5f);
    CHECK(ratio.mean().item<float>() >= 1 / 1.25f - 1e-5f);
    CHECK(ratio.mean().item<float>() <= 1.25f + 1e-5f);
  }
}

TEST_CASE("augment: the sampler applies it to training tuples, deterministically", "[data][augment]") {
  const auto g = test::make_tiny_dataset("augment_sampler", 12);
  HypersimOptions h;
  h.root = generated_hypersim_root(g.out);
  h.split = "all";
  TupleOptions plain;
  plain.width = 48, plain.height = 32, plain.targets = 2, plain.window = 6;
  TupleOptions aug = plain;
  aug.augment = all_on();
  TupleSampler p(read_hypersim(h).sequences, plain, 4), a1(read_hypersim(h).sequences, aug, 4),
      a2(read_hypersim(h).sequences, aug, 4);
  bool changed = false;
  for (int i = 0; i < 4; ++i) {
    const auto x = a1.sample(i), y = a2.sample(i), z = p.sample(i);
    CHECK(same_tuple(x, y));
    CHECK(x.context.name == z.context.name);  // the same frames, only transformed
    changed = changed || !same_tuple(x, z);
  }
  CHECK(changed);
}

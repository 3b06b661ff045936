// Renderer: closed-form cases, agreement with the dense per-pixel reference, finite-difference gradients,
// culling and input errors, batching, options, thread-count determinism and agreement of the SIMD levels; the
// contribution measure, pruning and merging.
#include <catch2/catch.hpp>

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <cmath>
#include <random>

#include "core/config.h"
#include "core/error.h"
#include "geometry/camera_torch.h"
#include "geometry/convert.h"
#include "render/kernels.h"
#include "render/lanes_avx512.h"
#include "render/merge.h"
#include "render/prune.h"
#include "render/render.h"
#include "render/tile_loop.h"
#include "support/finite_diff.h"
#include "support/reference_render.h"

using namespace isplat;
using torch::Tensor;

namespace {

const auto kF64 = torch::kFloat64;

// Restores LibTorch's thread count when a test that changes it ends, failed assertions included.
struct ThreadCountGuard {
  const int before = at::get_num_threads();
  ~ThreadCountGuard() { at::set_num_threads(before); }
};

// K with skew and a non-trivial pose, so projection and Jacobian exercise every term.
Camera make_camera(int64_t W, int64_t H, double fx, double fy, double skew, bool posed, torch::Dtype dt = kF64) {
  auto K = torch::tensor({fx, skew, 0.5 * W + 0.3, 0.0, fy, 0.5 * H - 0.2, 0.0, 0.0, 1.0}, kF64).reshape({3, 3});
  auto T = torch::eye(4, kF64);
  if (posed) {
    // Rotation of 0.2 rad about (1, 2, 3), translation (0.1, -0.2, 0.3).
    const double ang = 0.2;
    auto ax = torch::tensor({1.0, 2.0, 3.0}, kF64);
    ax = ax / ax.norm();
    auto Kx = torch::zeros({3, 3}, kF64);
    Kx[0][1] = -ax[2], Kx[0][2] = ax[1], Kx[1][0] = ax[2], Kx[1][2] = -ax[0], Kx[2][0] = -ax[1], Kx[2][1] = ax[0];
    auto R = torch::eye(3, kF64) + std::sin(ang) * Kx + (1 - std::cos(ang)) * torch::matmul(Kx, Kx);
    T.slice(0, 0, 3).slice(1, 0, 3).copy_(R);
    T.slice(0, 0, 3).select(1, 3).copy_(torch::tensor({0.1, -0.2, 0.3}, kF64));
  }
  return Camera{K, T, W, H}.to(dt);
}

// Camera-space points [N, 3] to world space for camera `cam`.
Tensor to_world(const Tensor& p_cam, const Camera& cam) {
  const Tensor T = cam.T_cw.to(kF64);
  const Tensor R = T.slice(0, 0, 3).slice(1, 0, 3), t = T.slice(0, 0, 3).select(1, 3);
  return torch::matmul(p_cam.to(kF64) - t, R).to(p_cam.scalar_type());
}

// n random Gaussians seen by `cam`: screen footprints of sigma_lo–sigma_hi px σ, depths 1–6, some beyond the
// frustum (spread > 1), opacities in [opac_lo, opac_hi].
Gaussians random_scene(int64_t n, const Camera& cam, uint64_t seed, double spread = 1.4, double sigma_lo = 0.5,
                       double sigma_hi = 6.0, double opac_lo = 0.05, double opac_hi = 1.02) {
  torch::manual_seed(seed);
  const double W = double(cam.width), H = double(cam.height), f = cam.K[0][0].item<double>();
  const Tensor z = 1.0 + 5.0 * torch::rand({n}, kF64);
  const Tensor u = W * (0.5 + spread * (torch::rand({n}, kF64) - 0.5));
  const Tensor v = H * (0.5 + spread * (torch::rand({n}, kF64) - 0.5));
  const Tensor uv = torch::stack({u, v}, 1);
  const Tensor p_cam = backproject_points(uv, z, cam.K.to(kF64));
  const Tensor sigma_px = torch::exp(std::log(sigma_lo) + std::log(sigma_hi / sigma_lo) * torch::rand({n, 1}, kF64));
  const Tensor aniso = torch::exp(0.6 * torch::randn({n, 3}, kF64));
  Gaussians g;
  g.means = to_world(p_cam, cam);
  g.scales = sigma_px * z.unsqueeze(1) / f * aniso;
  g.quats = torch::randn({n, 4}, kF64) * 1.7;
  g.colors = torch::rand({n, 3}, kF64);
  g.opacities = opac_lo + (opac_hi - opac_lo) * torch::rand({n}, kF64);  // some above 0.99 exercise the clamp
  return g;
}

struct Weights {
  Tensor rgb, depth, alpha;
};
Weights random_weights(int64_t H, int64_t W, uint64_t seed, torch::Dtype dt = kF64) {
  torch::manual_seed(seed);
  return {torch::randn({3, H, W}, dt), torch::randn({1, H, W}, dt) * 0.3, torch::randn({1, H, W}, dt)};
}

Tensor weighted_loss(const RenderOutput& o, const Weights& w) {
  return (o.rgb * w.rgb).sum() + (o.depth * w.depth).sum() + (o.alpha * w.alpha).sum();
}

Gaussians with_grad(const Gaussians& g) {
  Gaussians c = g.detach();
  for (Tensor* t : {&c.means, &c.scales, &c.quats, &c.colors, &c.opacities}) *t = t->clone().requires_grad_(true);
  return c;
}

std::vector<Tensor> grads_of(const Gaussians& g) {
  return {g.means.grad(), g.scales.grad(), g.quats.grad(), g.colors.grad(), g.opacities.grad()};
}
const char* kNames[] = {"means", "scales", "quats", "colors", "opacities"};

// Renders, back-propagates the weighted loss and returns rgb, alpha, depth, normal, then every gradient.
std::vector<Tensor> outputs_and_grads(const Gaussians& scene, const Camera& cam, const Weights& w,
                                      const RenderOptions& opt = {}, const RenderMaps& maps = {}) {
  const Gaussians a = with_grad(scene);
  const RenderOutput out = render(a, cam, opt, maps);
  weighted_loss(out, w).backward();
  std::vector<Tensor> r = {out.rgb, out.alpha, out.depth, out.normal};
  for (const Tensor& g : grads_of(a)) r.push_back(g);
  return r;
}

double max_abs(const Tensor& t) {
  return t.numel() ? t.abs().max().item<double>() : 0.0;
}

// One Gaussian per row of `rows`: camera-space mean (3), scales (3), opacity, colour (3); identity rotation.
Gaussians head_on(const std::vector<std::array<double, 10>>& rows) {
  std::vector<double> m, s, o, c, q;
  for (const auto& r : rows) {
    m.insert(m.end(), {r[0], r[1], r[2]});
    s.insert(s.end(), {r[3], r[4], r[5]});
    o.push_back(r[6]);
    c.insert(c.end(), {r[7], r[8], r[9]});
    q.insert(q.end(), {1.0, 0.0, 0.0, 0.0});
  }
  const int64_t n = int64_t(rows.size());
  return {torch::tensor(m, kF64).reshape({n, 3}), torch::tensor(s, kF64).reshape({n, 3}),
          torch::tensor(q, kF64).reshape({n, 4}), torch::tensor(c, kF64).reshape({n, 3}), torch::tensor(o, kF64)};
}

// Identity pose, square pixels, principal point on the centre of pixel (cx − 0.5, cy − 0.5).
Camera centred_camera(int64_t W, int64_t H, double f) {
  return Camera{make_K(f, f, 0.5 * W + 0.5, 0.5 * H + 0.5, kF64), torch::eye(4, kF64), W, H};
}

}  // namespace

TEST_CASE("render: one isotropic Gaussian seen head-on has the closed-form peak and width", "[render]") {
  // σ = f·s/z = 100·0.04/2 = 2 px, so the screen variance is 4 + 0.3 (dilation).
  const Camera cam = centred_camera(48, 32, 100.0);
  const Gaussians g = head_on({{0.0, 0.0, 2.0, 0.04, 0.04, 0.01, 0.6, 0.2, 0.5, 0.8}});
  RenderOptions opt;
  opt.background = {0.1, 0.2, 0.3};
  const double var = 4.0 + 0.3, c[3] = {0.2, 0.5, 0.8};
  for (bool aa : {false, true}) {
    opt.antialiased = aa;
    const RenderOutput out = render(g, cam, opt);
    REQUIRE(out.rgb.sizes() == torch::IntArrayRef({3, 32, 48}));
    const double o = aa ? 0.6 * 4.0 / var : 0.6;  // antialiased: o·sqrt(det Σ / det(Σ + 0.3 I)) = o·4/4.3
    const int64_t i0 = 16, j0 = 24;               // the pixel whose centre is the projected mean
    for (auto [di, dj] :
         std::vector<std::pair<int, int>>{{0, 0}, {0, 3}, {1, 2}, {-2, -3}, {4, 0}, {0, 6}, {0, 7}, {5, 5}}) {
      const double r2 = double(di * di + dj * dj);
      // Beyond 3σ (r² > 9·var) the pixel is cut; otherwise α = o·exp(−r²/(2σ²)).
      const double a = r2 > 9 * var ? 0.0 : o * std::exp(-0.5 * r2 / var);
      const int64_t i = i0 + di, j = j0 + dj;
      CAPTURE(aa, di, dj);
      CHECK(out.alpha[0][i][j].item<double>() == Approx(a).margin(1e-12));
      CHECK(out.depth[0][i][j].item<double>() == Approx(2.0 * a).margin(1e-12));
      for (int k = 0; k < 3; ++k)
        CHECK(out.rgb[k][i][j].item<double>() == Approx(a * c[k] + (1 - a) * opt.background[k]).margin(1e-12));
      // The thin axis is z; it faces the camera as −z.
      CHECK(out.normal[2][i][j].item<double>() == Approx(-a).margin(1e-12));
      CHECK(out.normal[0][i][j].item<double>() == Approx(0.0).margin(1e-12));
    }
    // The image total of alpha is the Gaussian's integral 2π·o·σ² within 3σ (1 − e^{−4.5} of it).
    CHECK(out.alpha.sum().item<double>() == Approx(2 * M_PI * o * var * (1 - std::exp(-4.5))).epsilon(0.02));
  }
}

TEST_CASE("render: opaque Gaussians are composited in depth order and occlude", "[render]") {
  const Camera cam = centred_camera(48, 32, 100.0);
  RenderOptions opt;
  opt.background = {0.0, 0.0, 1.0};
  // Green (big, z = 4, opacity 1 -> α clamped at 0.99) is listed before red (small, z = 2, opacity 0.9).
  const Gaussians g = head_on({{0.0, 0.0, 4.0, 0.2, 0.2, 0.2, 1.0, 0.0, 1.0, 0.0},       // σ = 5 px
                               {0.0, 0.0, 2.0, 0.04, 0.04, 0.04, 0.9, 1.0, 0.0, 0.0}});  // σ = 2 px
  const RenderOutput out = render(g, cam, opt);
  // Centre: red in front of green in front of blue background.
  CHECK(out.rgb[0][16][24].item<double>() == Approx(0.9).margin(1e-12));
  CHECK(out.rgb[1][16][24].item<double>() == Approx(0.1 * 0.99).margin(1e-12));
  CHECK(out.rgb[2][16][24].item<double>() == Approx(0.1 * 0.01).margin(1e-12));
  CHECK(out.alpha[0][16][24].item<double>() == Approx(1 - 0.1 * 0.01).margin(1e-12));
  CHECK(out.depth[0][16][24].item<double>() == Approx(0.9 * 2 + 0.1 * 0.99 * 4).margin(1e-12));
  // 8 px off centre red is beyond its 3σ: green alone, α = exp(−64 / (2·25.3)).
  const double a = std::exp(-64.0 / (2 * 25.3));
  CHECK(out.rgb[0][16][32].item<double>() == Approx(0.0).margin(1e-12));
  CHECK(out.rgb[1][16][32].item<double>() == Approx(a).margin(1e-12));
  CHECK(out.rgb[2][16][32].item<double>() == Approx(1 - a).margin(1e-12));
  // Moving red behind green: green now covers it (α 0.99 in front).
  Gaussians swapped = g;
  swapped.means = g.means.clone();
  swapped.means[1][2] = 6.0;
  swapped.scales = g.scales.clone();
  swapped.scales[1].fill_(0.12);  // still σ = 2 px at z = 6
  const RenderOutput back = render(swapped, cam, opt);
  CHECK(back.rgb[1][16][24].item<double>() == Approx(0.99).margin(1e-12));
  CHECK(back.rgb[0][16][24].item<double>() == Approx(0.01 * 0.9).margin(1e-12));

  // Early stop: after α = 0.98 and 0.99, T = 2e-4; a third Gaussian would take T below 1e-4, so it and
  // everything behind it are left out (T_final stays 2e-4).
  const Gaussians three = head_on({{0.0, 0.0, 2.0, 0.1, 0.1, 0.1, 0.98, 1.0, 0.0, 0.0},
                                   {0.0, 0.0, 3.0, 0.15, 0.15, 0.15, 0.996, 0.0, 1.0, 0.0},
                                   {0.0, 0.0, 4.0, 0.2, 0.2, 0.2, 0.7, 1.0, 1.0, 1.0}});
  const RenderOutput st = render(three, cam, opt);
  CHECK(st.alpha[0][16][24].item<double>() == Approx(1 - 0.02 * 0.01).margin(1e-14));
  CHECK(st.rgb[0][16][24].item<double>() == Approx(0.98).margin(1e-14));
  CHECK(st.rgb[2][16][24].item<double>() == Approx(0.02 * 0.01).margin(1e-14));  // background only
}

// Concatenation of Gaussian sets.
Gaussians concat(const std::vector<Gaussians>& sets) {
  std::vector<Tensor> m, s, q, c, o;
  for (const auto& g : sets)
    m.push_back(g.means), s.push_back(g.scales), q.push_back(g.quats), c.push_back(g.colors), o.push_back(g.opacities);
  return {torch::cat(m), torch::cat(s), torch::cat(q), torch::cat(c), torch::cat(o)};
}

TEST_CASE("render: forward and gradients match the dense per-pixel reference", "[render]") {
  // 70×45 leaves partial tiles on two sides. Three populations: a few hundred small Gaussians (some beyond
  // the frustum), large ones spanning many tiles, and a dense opaque cluster where pixels reach the
  // T < 1e-4 stop.
  const Camera cam = make_camera(70, 45, 55.0, 58.0, 0.8, true);
  const Gaussians scene = concat({random_scene(300, cam, 7), random_scene(12, cam, 8, 1.2, 10.0, 25.0, 0.05, 0.6),
                                  random_scene(60, cam, 9, 0.3, 3.0, 8.0, 0.9, 1.0)});
  const Weights w = random_weights(45, 70, 10);
  for (bool aa : {false, true}) {
    RenderOptions opt;
    opt.background = {0.3, 0.6, 0.9};
    opt.antialiased = aa;
    const Gaussians a = with_grad(scene), b = with_grad(scene);
    const RenderOutput out = render(a, cam, opt);
    const RenderOutput ref = test::reference_render(b, cam, opt);
    CAPTURE(aa);
    CHECK(max_abs(out.rgb - ref.rgb) < 1e-10);
    CHECK(max_abs(out.alpha - ref.alpha) < 1e-10);
    CHECK(max_abs(out.depth - ref.depth) < 1e-9);
    CHECK(max_abs(out.normal - ref.normal) < 1e-10);
    CHECK(out.alpha.max().item<double>() > 0.999);  // the opaque cluster is opaque
    weighted_loss(out, w).backward();
    weighted_loss(ref, w).backward();
    const auto ga = grads_of(a), gb = grads_of(b);
    for (int k = 0; k < 5; ++k) {
      CAPTURE(kNames[k]);
      const double scale = max_abs(gb[k]);
      CHECK(scale > 0);
      CHECK(max_abs(ga[k] - gb[k]) <= 1e-7 * scale);
    }
  }
}

TEST_CASE("render: float32 agrees with float64", "[render]") {
  const Camera cam = make_camera(64, 48, 55.0, 58.0, 0.8, true);
  const Gaussians scene = random_scene(300, cam, 11);
  const RenderOutput d = render(scene, cam);
  const RenderOutput f = render(scene.to(torch::kFloat32), cam.to(torch::kFloat32));
  CHECK(f.rgb.scalar_type() == torch::kFloat32);
  // A pixel exactly on a cut boundary may flip; on average the two must agree to float precision.
  CHECK((f.rgb.to(kF64) - d.rgb).abs().mean().item<double>() < 1e-5);
  CHECK((f.depth.to(kF64) - d.depth).abs().mean().item<double>() < 1e-4);
  CHECK((f.alpha.to(kF64) - d.alpha).abs().mean().item<double>() < 1e-5);
}

TEST_CASE("render: gradients of rgb depth and alpha match central finite differences", "[render]") {
  // Six overlapping, tilted Gaussians at depths 1.5–4.5 in a 32×24 image; one is opaque enough to be
  // clamped at its centre, one lies beyond 1.15× the image width (Jacobian clamped) but reaches inside.
  const Camera cam = make_camera(32, 24, 30.0, 32.0, 0.7, true);
  const Tensor p_cam = torch::tensor({0.10, 0.05, 2.0, -0.20, 0.10, 2.5, 0.30, -0.20, 3.5, 0.0, 0.0, 1.5, 1.20, 0.10,
                                      1.6, -0.30, -0.25, 4.5},
                                     kF64)
                           .reshape({6, 3});
  Gaussians g;
  g.means = to_world(p_cam, cam);
  g.scales = torch::tensor({0.25, 0.12, 0.05, 0.15, 0.30, 0.10, 0.90, 0.60, 0.70, 0.08, 0.10, 0.06, 0.50, 0.30, 0.20,
                            0.20, 0.25, 0.15},
                           kF64)
                 .reshape({6, 3});
  torch::manual_seed(3);
  g.quats = torch::randn({6, 4}, kF64) * 1.5;
  g.colors = torch::rand({6, 3}, kF64);
  g.opacities = torch::tensor({0.7, 0.6, 1.0, 0.5, 0.8, 0.4}, kF64);
  const Weights w = random_weights(24, 32, 4);
  for (bool aa : {false, true}) {
    RenderOptions opt;
    opt.background = {0.2, 0.4, 0.6};
    opt.antialiased = aa;
    auto f = [&](const std::vector<Tensor>& x) {
      const RenderOutput o = render(Gaussians{x[0], x[1], x[2], x[3], x[4]}, cam, opt);
      return torch::stack({(o.rgb * w.rgb).sum(), (o.depth * w.depth).sum(), (o.alpha * w.alpha).sum()});
    };
    const auto r = test::check_gradients(f, {g.means, g.scales, g.quats, g.colors, g.opacities},
                                         {"means", "scales", "quats", "colors", "opacities"}, 1e-6, 1e-6, 1e-5);
    CAPTURE(aa, r.report, r.max_abs_error);
    CHECK(r.checked == 6 * 14 * 3);
    CHECK(r.ok);
  }
}

TEST_CASE("render: culled Gaussians contribute nothing and never give NaN", "[render]") {
  const Camera cam = make_camera(40, 30, 40.0, 40.0, 0.0, false);
  // Row 0 is an ordinary Gaussian; the others must all be culled.
  Gaussians g = head_on({{0.0, 0.0, 2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 0.5, 0.2},    // visible
                         {0.0, 0.0, -2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 1.0, 1.0},   // behind the camera
                         {0.0, 0.0, 0.005, 0.1, 0.1, 0.1, 0.8, 1.0, 1.0, 1.0},  // in front of the near plane
                         {0.1, 0.0, 2.0, 0.1, 0.1, 0.1, 0.0, 1.0, 1.0, 1.0},    // zero opacity
                         {0.1, 0.0, 2.0, 0.1, 0.0, 0.1, 0.8, 1.0, 1.0, 1.0},    // zero scale
                         {0.1, 0.0, 2.0, 0.1, 0.1, 0.1, 0.003, 1.0, 1.0, 1.0},  // can never reach 1/255
                         {-90.0, 0.0, 2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 1.0, 1.0},  // far off screen
                         {0.0, 0.1, 2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 1.0, 1.0}});  // zero quaternion (below)
  g.quats[7].zero_();
  for (torch::Dtype dt : {torch::kFloat32, kF64}) {
    const Gaussians a = with_grad(g.to(dt));
    const RenderOutput out = render(a, cam.to(dt));
    weighted_loss(out, random_weights(30, 40, 1, dt)).backward();
    const RenderOutput alone = render(g.to(dt).index(torch::tensor({0}, torch::kInt64)), cam.to(dt));
    CAPTURE(dt);
    CHECK(torch::equal(out.rgb, alone.rgb));
    CHECK(torch::equal(out.depth, alone.depth));
    for (const Tensor& t : grads_of(a)) {
      CHECK(torch::isfinite(t).all().item<bool>());
      CHECK(max_abs(t.slice(0, 1)) == 0.0);
    }
    CHECK(max_abs(a.means.grad()[0]) > 0);
  }
  // Extreme but finite values: a huge scale overflows the float covariance, a Gaussian just past the near
  // plane at the frustum edge has a huge footprint. Neither may turn into NaN.
  Gaussians x = head_on({{0.0, 0.0, 2.0, 1e20, 1e20, 1e20, 0.8, 1.0, 1.0, 1.0},
                         {5.0, 3.0, 0.0100001, 0.01, 0.02, 0.01, 0.8, 0.0, 1.0, 0.0},
                         {0.0, 0.0, 3.0, 0.1, 0.1, 0.1, 0.8, 1.0, 0.0, 0.0}});
  for (torch::Dtype dt : {torch::kFloat32, kF64}) {
    const Gaussians a = with_grad(x.to(dt));
    const RenderOutput out = render(a, cam.to(dt));
    weighted_loss(out, random_weights(30, 40, 2, dt)).backward();
    CAPTURE(dt);
    for (const Tensor& t : {out.rgb, out.alpha, out.depth, out.normal}) CHECK(torch::isfinite(t).all().item<bool>());
    for (const Tensor& t : grads_of(a)) CHECK(torch::isfinite(t).all().item<bool>());
  }
}

TEST_CASE("render: invalid inputs are rejected with a clear error", "[render]") {
  const Camera cam = make_camera(16, 16, 20.0, 20.0, 0.0, false);
  const Gaussians g =
      head_on({{0.0, 0.0, 2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 0.5, 0.2}, {0.1, 0.0, 2.0, 0.1, 0.1, 0.1, 0.8, 1.0, 0.5, 0.2}});
  Gaussians bad = g;
  bad.means = g.means.clone();
  bad.means[1][0] = std::nan("");
  CHECK_THROWS_WITH(render(bad, cam), Catch::Contains("render: means has 1 non-finite value"));
  bad = g;
  bad.opacities = g.opacities.clone();
  bad.opacities.fill_(INFINITY);
  CHECK_THROWS_WITH(render(bad, cam), Catch::Contains("render: opacities has 2 non-finite values"));
  bad = g;
  bad.quats = g.quats.slice(1, 0, 3);
  CHECK_THROWS_WITH(render(bad, cam), Catch::Contains("quats must be [2, 4]"));
  bad = g;
  bad.colors = g.colors.to(torch::kFloat32);
  CHECK_THROWS_AS(render(bad, cam), Error);
  RenderOptions opt;
  opt.background = {1.0, 1.0};
  CHECK_THROWS_WITH(render(g, cam, opt), Catch::Contains("background must have 3 values"));
  const Camera two = stack_cameras({cam, cam});
  Gaussians three{g.means.unsqueeze(0).expand({3, 2, 3}), g.scales.unsqueeze(0).expand({3, 2, 3}),
                  g.quats.unsqueeze(0).expand({3, 2, 4}), g.colors.unsqueeze(0).expand({3, 2, 3}),
                  g.opacities.unsqueeze(0).expand({3, 2})};
  CHECK_THROWS_WITH(render(three, two), Catch::Contains("3 Gaussian sets but 2 cameras"));
}

TEST_CASE("render: batches of cameras and of Gaussian sets", "[render]") {
  const Camera c0 = make_camera(32, 24, 30.0, 30.0, 0.0, false), c1 = make_camera(32, 24, 30.0, 30.0, 0.5, true);
  const Camera cams = stack_cameras({c0, c1});
  const Gaussians s0 = random_scene(40, c0, 21, 1.0), s1 = random_scene(40, c0, 22, 1.0);

  // One set, two cameras: equal to two single renders, gradients summed.
  const Gaussians a = with_grad(s0), b = with_grad(s0);
  const RenderOutput batch = render(a, cams);
  REQUIRE(batch.rgb.sizes() == torch::IntArrayRef({2, 3, 24, 32}));
  REQUIRE(batch.alpha.sizes() == torch::IntArrayRef({2, 1, 24, 32}));
  const RenderOutput o0 = render(b, c0), o1 = render(b, c1);
  CHECK(torch::equal(batch.rgb[0], o0.rgb));
  CHECK(torch::equal(batch.depth[1], o1.depth));
  CHECK(!torch::equal(o0.rgb, o1.rgb));
  (batch.rgb.sum() + batch.depth.sum()).backward();
  (o0.rgb.sum() + o0.depth.sum() + o1.rgb.sum() + o1.depth.sum()).backward();
  CHECK(torch::allclose(a.means.grad(), b.means.grad(), 1e-12, 1e-12));
  CHECK(torch::allclose(a.quats.grad(), b.quats.grad(), 1e-12, 1e-12));

  // Two sets, two cameras: set b through camera b.
  Gaussians sets{torch::stack({s0.means, s1.means}), torch::stack({s0.scales, s1.scales}),
                 torch::stack({s0.quats, s1.quats}), torch::stack({s0.colors, s1.colors}),
                 torch::stack({s0.opacities, s1.opacities})};
  sets = with_grad(sets);
  const RenderOutput pairs = render(sets, cams);
  CHECK(torch::equal(pairs.rgb[1], render(s1, c1).rgb));
  CHECK(torch::equal(pairs.normal[0], render(s0, c0).normal));
  pairs.alpha.sum().backward();
  CHECK(sets.opacities.grad().sizes() == torch::IntArrayRef({2, 40}));
  CHECK(max_abs(sets.opacities.grad()[1]) > 0);
  // Two sets, one camera.
  CHECK(torch::equal(render(sets, c0).rgb[1].detach(), render(s1, c0).rgb));
}

TEST_CASE("render: an empty set renders the background", "[render]") {
  const Camera cam = make_camera(20, 10, 20.0, 20.0, 0.0, false);
  Gaussians g = with_grad(Gaussians{torch::zeros({0, 3}, kF64), torch::zeros({0, 3}, kF64), torch::zeros({0, 4}, kF64),
                                    torch::zeros({0, 3}, kF64), torch::zeros({0}, kF64)});
  RenderOptions opt;
  opt.background = {0.25, 0.5, 1.0};
  const RenderOutput out = render(g, cam, opt);
  CHECK(torch::allclose(out.rgb[2], torch::ones({10, 20}, kF64)));
  CHECK(out.alpha.abs().sum().item<double>() == 0.0);
  out.rgb.sum().backward();
  CHECK(g.means.grad().sizes() == torch::IntArrayRef({0, 3}));
}

TEST_CASE("render: bit-identical results with 1 and 2 threads", "[render]") {
  const Camera cam = make_camera(160, 120, 130.0, 130.0, 0.3, true, torch::kFloat32);
  const Gaussians scene = random_scene(3000, cam, 5).to(torch::kFloat32);
  const Weights w = random_weights(120, 160, 6, torch::kFloat32);
  std::vector<std::vector<Tensor>> results;
  {
    const ThreadCountGuard guard;
    for (int threads : {1, 2}) {
      at::set_num_threads(threads);
      results.push_back(outputs_and_grads(scene, cam, w));
    }
  }
  REQUIRE(results[0].size() == results[1].size());
  for (size_t k = 0; k < results[0].size(); ++k) {
    CAPTURE(k);
    CHECK(torch::equal(results[0][k], results[1][k]));
  }
  CHECK(results[0][1].max().item<float>() > 0.5f);
}

TEST_CASE("render: tile binning lists each tile's Gaussians by (depth, id), whatever the thread count", "[render]") {
  // 20000 Gaussians (several compaction blocks), some culled, and 2000 exact copies so that depths tie; on a
  // 117-tile image, and on a 2-tile one where threads outnumber tiles.
  const auto [W, H] = GENERATE(std::pair<int64_t, int64_t>{200, 136}, std::pair<int64_t, int64_t>{24, 16});
  CAPTURE(W, H);
  const Camera cam = make_camera(W, H, 0.75 * double(W), 0.75 * double(W), 0.0, true, torch::kFloat32);
  Gaussians g = random_scene(18000, cam, 21, 1.6).to(torch::kFloat32);
  const Tensor copies = torch::arange(0, 18000, 9);
  for (Tensor* t : {&g.means, &g.scales, &g.quats, &g.colors, &g.opacities})
    *t = torch::cat({*t, t->index_select(0, copies)}).contiguous();
  const splat::CameraParams cp = splat::camera_params(cam.K, cam.T_cw, cam.width, cam.height);
  const splat::Projection proj = splat::project_fwd(g.means, g.scales, g.quats, g.colors, g.opacities, cp, {});
  const int64_t n = g.means.size(0), tiles_x = cp.tiles_x(), tiles = tiles_x * cp.tiles_y();
  const float* rec = proj.packed.data_ptr<float>();
  const int32_t* rect = proj.rects.data_ptr<int32_t>();

  // Reference: for every tile, the ids whose rectangle covers it, sorted by (depth, id).
  std::vector<std::vector<int32_t>> expected(static_cast<size_t>(tiles));
  int64_t culled = 0;
  for (int64_t i = 0; i < n; ++i) {
    const int32_t* r = rect + 4 * i;
    culled += !(r[0] < r[2] && r[1] < r[3]);
    for (int32_t ty = r[1]; ty < r[3]; ++ty)
      for (int32_t tx = r[0]; tx < r[2]; ++tx) expected[size_t(ty * tiles_x + tx)].push_back(int32_t(i));
  }
  for (auto& list : expected)
    std::stable_sort(list.begin(), list.end(), [&](int32_t a, int32_t b) {
      return rec[a * splat::kRec + splat::kDepth] < rec[b * splat::kRec + splat::kDepth];
    });
  CHECK(culled > 1000);
  int64_t ties = 0;
  for (const auto& list : expected)
    for (size_t k = 1; k < list.size(); ++k)
      ties += rec[list[k] * splat::kRec + splat::kDepth] == rec[list[k - 1] * splat::kRec + splat::kDepth];
  CHECK(ties > 100);

  const ThreadCountGuard guard;
  for (int threads : {1, 2, 3}) {
    CAPTURE(threads);
    at::set_num_threads(threads);
    const splat::TileBins bins = splat::bin_tiles(proj, cp);
    const int64_t* offs = bins.tile_offsets.data_ptr<int64_t>();
    const int32_t* ids = bins.isect_ids.data_ptr<int32_t>();
    REQUIRE(bins.tile_offsets.numel() == tiles + 1);
    CHECK(offs[0] == 0);
    int64_t wrong = 0;
    for (int64_t t = 0; t < tiles; ++t)
      wrong += std::vector<int32_t>(ids + offs[t], ids + offs[t + 1]) != expected[size_t(t)];
    CHECK(wrong == 0);
    CHECK(offs[tiles] == bins.intersections());
  }
}

TEST_CASE("render: options read and write through the config schema", "[render]") {
  const auto json = config_to_json(RenderOptions{});
  CHECK(json["background"].get<std::vector<double>>() == std::vector<double>{0.0, 0.0, 0.0});
  CHECK(json["antialiased"] == false);
  CHECK(json["near"] == 0.01);
  CHECK(json["dilation"] == 0.3);
  CHECK(json.size() == 5);  // config keys only: which maps to composite is RenderMaps, per call
  const auto o = config_from_json<RenderOptions>({{"background", {1, 1, 1}}, {"antialiased", true}}, "test");
  CHECK(o.antialiased);
  CHECK(o.background == std::vector<double>{1, 1, 1});
  CHECK_THROWS_AS(config_from_json<RenderOptions>({{"near", 0}}, "test"), Error);
}

namespace {
// The SIMD levels this CPU runs, portable first. A level the CPU lacks cannot be checked here: say so.
std::vector<splat::Simd> simd_levels() {
  std::vector<splat::Simd> levels;
  for (auto level : {splat::Simd::portable, splat::Simd::avx2, splat::Simd::avx512}) {
    if (level <= splat::simd_supported())
      levels.push_back(level);
    else
      WARN("this CPU has no " << splat::simd_name(level) << ": its pixel loops and projection are not checked here");
  }
  return levels;
}
}  // namespace

TEST_CASE("render: every SIMD level's pixel loops agree bit for bit", "[render]") {
  // Double precision (the finite-difference and reference tests) always takes the portable loops; this ties
  // the float AVX2 and AVX-512 loops to them. Large and small splats, so that Gaussians cover odd and even
  // numbers of 8-pixel groups (AVX-512 pairs them and finishes an odd one on the AVX2 rule). 100x84 leaves the
  // last tile column and row partial.
  const Camera cam = make_camera(100, 84, 80.0, 80.0, 0.3, true, torch::kFloat32);
  const Weights w = random_weights(84, 100, 16, torch::kFloat32);
  for (bool large : {false, true}) {
    CAPTURE(large);
    const Gaussians scene =
        (large ? random_scene(300, cam, 15, 1.4, 4.0, 20.0) : random_scene(1500, cam, 15)).to(torch::kFloat32);
    std::vector<std::vector<Tensor>> results;
    for (splat::Simd level : simd_levels()) {
      const splat::Simd before = splat::set_simd_level(level);
      RenderOptions opt;
      opt.background = {0.2f, 0.3f, 0.4f};
      results.push_back(outputs_and_grads(scene, cam, w, opt));
      opt.depth = "plane";
      results.back().push_back(render(scene, cam, opt).depth);
      splat::set_simd_level(before);
    }
    for (size_t level = 1; level < results.size(); ++level)
      for (size_t k = 0; k < results[0].size(); ++k) {
        CAPTURE(splat::simd_name(splat::Simd(level)), k);
        CHECK(torch::equal(results[0][k], results[level][k]));
      }
    CHECK(max_abs(results[0][4]) > 0);
  }
}

namespace {
// For a test of a SIMD level this CPU lacks: what can still be checked is that those loops never run here, because
// asking for the level gives the CPU's best. `what` says what goes unchecked.
void check_level_falls_back(splat::Simd missing, const char* what) {
  const splat::Simd before = splat::set_simd_level(missing);
  CHECK(splat::simd_level() == splat::simd_supported());
  splat::set_simd_level(before);
  WARN("this CPU has no " << splat::simd_name(missing) << ": " << what);
}
}  // namespace

TEST_CASE(
    "render: the forward's group hits are the groups it composited, and the backward gives the same "
    "gradients with or without them",
    "[render]") {
  if (splat::simd_supported() < splat::Simd::avx2) {
    check_level_falls_back(splat::Simd::avx2, "the group hits are not recorded, so not checked here");
    return;
  }
  const Camera cam = make_camera(100, 84, 80.0, 80.0, 0.3, true, torch::kFloat32);
  const splat::CameraParams cp = splat::camera_params(cam.K, cam.T_cw, 100, 84);
  const Gaussians scene = concat({random_scene(1500, cam, 21), random_scene(200, cam, 22, 1.4, 4.0, 20.0)});
  const Gaussians g = scene.to(torch::kFloat32);
  const double bg[3] = {0.2, 0.3, 0.4};
  struct SimdGuard {  // restores the level when the test ends, failed REQUIREs included
    const splat::Simd before = splat::simd_level();
    ~SimdGuard() { splat::set_simd_level(before); }
  } guard;
  const splat::Projection proj = splat::project_fwd(g.means, g.scales, g.quats, g.colors, g.opacities, cp, {});
  const splat::TileBins bins = splat::bin_tiles(proj, cp);
  auto forward_at = [&](splat::Simd level) {
    splat::set_simd_level(level);
    return splat::rasterize_fwd(proj.packed, bins, cp, bg, {false, false, true});
  };
  const std::vector<splat::Simd> levels = simd_levels();  // portable first
  CHECK(forward_at(splat::Simd::portable).group_hits.numel() == 0);
  const splat::RasterOutput out = forward_at(splat::Simd::avx2);
  REQUIRE(out.group_hits.numel() == bins.intersections());
  CHECK(splat::rasterize_fwd(proj.packed, bins, cp, bg, {false, false, false}).group_hits.numel() == 0);  // not asked
  if (levels.back() == splat::Simd::avx512)
    CHECK(torch::equal(forward_at(splat::Simd::avx512).group_hits, out.group_hits));
  // Each entry's bits against its pixels: group (row r, half h) is set iff the entry is some pixel's contributor
  // there, by the per-pixel rule in double (1 + its tile-local index ≤ the pixel's last contributor, and it passes
  // the cut and the 1/255 test). Pixels within 0.1% of either test's edge may go either way in float, so a bit
  // must be set where a pixel passes with that margin, and may be set only where one passes without it.
  const auto offs = bins.tile_offsets.accessor<int64_t, 1>();
  const auto ids = bins.isect_ids.accessor<int32_t, 1>();
  const auto hits = out.group_hits.accessor<int32_t, 1>();
  const auto rec = proj.packed.accessor<float, 2>();
  const auto last = out.n_contrib.accessor<int32_t, 2>();
  const int64_t tiles_x = cp.tiles_x();
  int64_t set = 0, checked = 0, mismatched = 0;
  for (int64_t t = 0; t + 1 < offs.size(0); ++t) {
    const int64_t x0 = (t % tiles_x) * 16, y0 = (t / tiles_x) * 16;
    for (int64_t k = offs[t]; k < offs[t + 1]; ++k) {
      const int64_t i = k - offs[t];
      const auto r = rec[ids[k]];
      uint32_t expect = 0, maybe = 0;
      for (int64_t py = y0; py < std::min<int64_t>(y0 + 16, 84); ++py)
        for (int64_t px = x0; px < std::min<int64_t>(x0 + 16, 100); ++px) {
          const double dx = px + 0.5 - r[splat::kU], dy = py + 0.5 - r[splat::kV];
          const double power =
              0.5 * (r[splat::kConA] * dx * dx + r[splat::kConC] * dy * dy) + r[splat::kConB] * dx * dy;
          const double raw = r[splat::kOpac] * std::exp(-power);
          if (power > 1.001 * r[splat::kCut] || raw < 0.999 / 255 || i + 1 > last[py][px]) continue;
          const uint32_t bit = 1u << ((px - x0) / 8 * 16 + (py - y0));
          maybe |= bit;
          if (power <= 0.999 * r[splat::kCut] && raw >= 1.001 / 255) expect |= bit;
        }
      const uint32_t got = uint32_t(hits[k]);
      set += got != 0;
      ++checked;
      mismatched += (expect & ~got) != 0 || (got & ~maybe) != 0;
    }
  }
  CHECK(checked == bins.intersections());
  CHECK(set > checked / 4);
  CHECK(mismatched == 0);
  // The backward at every level after a forward at every level: with the hits (a forward that recorded them and a
  // backward that reads them, across levels too), without them (a portable forward records none) and with them
  // ignored (a portable backward): the same gradients, bit for bit.
  const Weights w = random_weights(84, 100, 23, torch::kFloat32);
  std::vector<std::vector<Tensor>> grads;
  for (splat::Simd fwd : levels)
    for (splat::Simd bwd : levels) {
      splat::set_simd_level(fwd);
      const Gaussians a = with_grad(g);
      const Tensor loss = weighted_loss(render(a, cam), w);
      splat::set_simd_level(bwd);
      loss.backward();
      grads.push_back(grads_of(a));
    }
  for (size_t run = 1; run < grads.size(); ++run)
    for (int k = 0; k < 5; ++k) {
      CAPTURE(run, kNames[k]);
      CHECK(torch::equal(grads[0][k], grads[run][k]));
    }
  CHECK(max_abs(grads[0][0]) > 0);
}

TEST_CASE("render: every SIMD level's projection agrees bit for bit, culled and non-finite inputs included",
          "[render]") {
  // The projection runs a block of Gaussians per vector (4 or 8 lanes), built once per level; this ties the levels
  // together (the reference and finite-difference tests check the projection itself). A mixed set: in view, behind
  // the camera, outside the 1.3x frustum (clamped Jacobian), degenerate, non-finite, whole blocks with no gradient
  // (rows 32..47), and a partial last block (5003 is odd).
  for (bool antialiased : {false, true}) {
    CAPTURE(antialiased);
    torch::manual_seed(7);
    const int64_t n = 5003;
    Tensor means = torch::randn({n, 3}) * 2, scales = torch::rand({n, 3}) * 0.3 + 1e-4;
    Tensor quats = torch::randn({n, 4}), colors = torch::rand({n, 3}), opacities = torch::rand({n});
    means.select(1, 2).add_(3.0);
    means[5][0] = NAN, scales[7][1] = INFINITY, colors[8][2] = NAN, quats[9].zero_(), opacities[11] = 0;
    scales[13][2] = -1, opacities[17] = 0.001f;
    const Tensor K = torch::tensor({{120.0, 0.5, 64.0}, {0.0, 110.0, 48.0}, {0.0, 0.0, 1.0}}, kF64);
    Tensor T_cw = torch::eye(4, kF64);
    T_cw[0][3] = 0.1, T_cw[1][3] = -0.2;
    const splat::CameraParams cam = splat::camera_params(K, T_cw, 128, 96);
    splat::ProjectSettings settings;
    settings.antialiased = antialiased;
    const Tensor grad2d = torch::randn({n, splat::kGrad2d});
    grad2d[21].zero_();
    grad2d.narrow(0, 32, 16).zero_();
    std::vector<std::vector<Tensor>> results;
    for (splat::Simd level : simd_levels()) {
      const splat::Simd before = splat::set_simd_level(level);
      const auto p = splat::project_fwd(means, scales, quats, colors, opacities, cam, settings);
      const auto g = splat::project_bwd(means, scales, quats, opacities, cam, settings, grad2d);
      splat::set_simd_level(before);
      results.push_back({p.packed, p.rects, g.means, g.scales, g.quats, g.opacities,
                         torch::tensor(std::vector<int64_t>(p.nonfinite, p.nonfinite + 5))});
    }
    const Tensor visible = results[0][1].select(1, 2) > results[0][1].select(1, 0);
    CHECK(visible.sum().item<int64_t>() > 2000);
    CHECK(visible.sum().item<int64_t>() < n - 1000);
    CHECK(torch::equal(results[0][6], torch::tensor({1, 1, 0, 1, 0}, torch::kInt64)));  // rows 5, 7, 8
    for (int64_t row : {5, 7, 8, 9, 11, 13, 17}) {  // non-finite, zero quaternion, zero opacity, negative scale,
      CAPTURE(row);                                 // too faint: zero records and empty rectangles
      CHECK(max_abs(results[0][0][row]) == 0);
      CHECK(max_abs(results[0][1][row]) == 0);
    }
    CHECK(max_abs(results[0][2]) > 0);
    CHECK(max_abs(results[0][2].narrow(0, 32, 16)) == 0);  // no gradient in, none out
    CHECK(max_abs(results[0][5][21]) == 0);
    for (size_t level = 1; level < results.size(); ++level)
      for (size_t k = 0; k < results[0].size(); ++k) {
        CAPTURE(splat::simd_name(splat::Simd(level)), k);
        CHECK(torch::equal(results[0][k], results[level][k]));
      }
  }
}

#ifdef ISPLAT_HAVE_AVX2_LANES
namespace {
// The AVX-512 forward's pixel boxes of one block, from a function built for AVX-512 (as the forward is). GCC 12's
// intrinsics seed some results with _mm512_undefined_pd, which -Wuninitialized reports where they are inlined.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
ISPLAT_AVX512_FN void vector_boxes(const float* rec, int64_t n, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                                   splat::PixelBoxes& out) {
  splat::pixel_boxes(rec, n, x0, y0, x1, y1, out);
}
#pragma GCC diagnostic pop
}  // namespace
#endif

TEST_CASE("render: the AVX-512 forward's pixel boxes are pixel_box's", "[render]") {
#ifdef ISPLAT_HAVE_AVX2_LANES
  if (splat::simd_supported() < splat::Simd::avx512) {
    check_level_falls_back(splat::Simd::avx512, "its pixel boxes are not checked here");
    return;
  }
  // Records in and around a 100x70 image (partial tiles at its right and bottom); a third sit exactly on a
  // pixel-centre boundary (u − rx − 0.5 or v + ry − 0.5 an integer), where a rounding slip would show. The last
  // block is partial: its gathers must not reach past the records.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> pos(-30.0f, 130.0f), extent(0.0f, 40.0f);
  std::uniform_int_distribution<int> quarter(0, 160), whole(-20, 110);
  const int64_t count = 16 * 37 + 7, W = 100, H = 70;
  std::vector<float> records(size_t(count * splat::kRec), 0.0f);
  for (int64_t i = 0; i < count; ++i) {
    float* r = records.data() + i * splat::kRec;
    r[splat::kU] = pos(rng), r[splat::kV] = pos(rng), r[splat::kRx] = extent(rng), r[splat::kRy] = extent(rng);
    if (i % 3 == 0) {
      r[splat::kRx] = 0.25f * float(quarter(rng)), r[splat::kRy] = 0.25f * float(quarter(rng));
      r[splat::kU] = float(whole(rng)) + 0.5f + r[splat::kRx];
      r[splat::kV] = float(whole(rng)) + 0.5f - r[splat::kRy];
    }
  }
  int64_t boxes = 0, empty = 0;
  for (int64_t y0 = 0; y0 < H; y0 += splat::kTile)
    for (int64_t x0 = 0; x0 < W; x0 += splat::kTile) {
      const int64_t x1 = std::min(x0 + splat::kTile, W), y1 = std::min(y0 + splat::kTile, H);
      for (int64_t b = 0; b < count; b += 16) {
        splat::PixelBoxes out;
        vector_boxes(records.data() + b * splat::kRec, count - b, x0, y0, x1, y1, out);
        for (int64_t k = 0; k < std::min<int64_t>(16, count - b); ++k) {
          int64_t ys = 0, ye = 0, g0 = 0, g1 = 0, vys = 0, vye = 0, vg0 = 0, vg1 = 0;
          const bool scalar = splat::pixel_box(records.data() + (b + k) * splat::kRec, x0, y0, x1, y1, ys, ye, g0, g1);
          const bool vector = out.unpack(int(k), y0, vys, vye, vg0, vg1);
          CAPTURE(b + k, x0, y0);
          REQUIRE(vector == scalar);
          if (!scalar) {
            ++empty;
            continue;
          }
          ++boxes;
          CHECK(vys == ys);
          CHECK(vye == ye);
          CHECK(vg0 == g0);
          CHECK(vg1 == g1);
        }
      }
    }
  CHECK(boxes > 1000);
  CHECK(empty > 1000);
#else
  WARN("no x86-64 vector loops in this build: the pixel boxes are not checked here");
#endif
}

TEST_CASE("render: leaving the normal map out changes nothing else", "[render]") {
  // The trainer renders without normals; its images and gradients must be those of the full render, on both
  // the AVX2 and the portable loops, in float and double.
  for (auto dtype : {torch::kFloat32, torch::kFloat64}) {
    for (splat::Simd level : simd_levels()) {
      CAPTURE(dtype, splat::simd_name(level));
      const splat::Simd before = splat::set_simd_level(level);
      const Camera cam = make_camera(96, 80, 80.0, 80.0, 0.3, true, dtype);
      const Gaussians scene = random_scene(800, cam, 21).to(dtype);
      const Weights w = random_weights(80, 96, 22, dtype);
      RenderMaps without;
      without.normals = false;
      const auto full = outputs_and_grads(scene, cam, w), lean = outputs_and_grads(scene, cam, w, {}, without);
      splat::set_simd_level(before);
      CHECK(full[3].sizes() == torch::IntArrayRef({3, 80, 96}));
      CHECK(max_abs(full[3]) > 0.5);
      CHECK(lean[3].numel() == 0);
      for (size_t k = 0; k < full.size(); ++k) {
        if (k == 3) continue;
        CAPTURE(k);
        CHECK(torch::equal(full[k], lean[k]));
      }
    }
  }
}

TEST_CASE("render: outputs no loss reads get no gradient, and the others' gradients are unchanged", "[render]") {
  // The autograd function leaves unread outputs' gradients undefined. A loss on alpha alone or on depth alone (the
  // colour gradient then absent) must give what the same loss with zero-weighted other terms gives, at every level.
  const Camera cam = make_camera(64, 48, 60.0, 60.0, 0.2, true, torch::kFloat32);
  const Gaussians scene = random_scene(400, cam, 25).to(torch::kFloat32);
  const Weights w = random_weights(48, 64, 26, torch::kFloat32);
  for (splat::Simd level : simd_levels()) {
    for (const char* only : {"alpha", "depth"}) {
      CAPTURE(splat::simd_name(level), only);
      const splat::Simd before = splat::set_simd_level(level);
      const bool alpha = std::string(only) == "alpha";
      const Gaussians a = with_grad(scene), b = with_grad(scene);
      const RenderOutput oa = render(a, cam), ob = render(b, cam);
      (alpha ? (oa.alpha * w.alpha).sum() : (oa.depth * w.depth).sum()).backward();
      const Tensor read = alpha ? (ob.alpha * w.alpha).sum() : (ob.depth * w.depth).sum();
      (read + 0.0 * ob.rgb.sum() + 0.0 * (alpha ? ob.depth : ob.alpha).sum()).backward();
      splat::set_simd_level(before);
      const auto ga = grads_of(a), gb = grads_of(b);
      for (size_t k = 0; k < ga.size(); ++k) {
        if (k == 3) continue;  // colours: no gradient from alpha or depth
        CAPTURE(kNames[k]);
        REQUIRE(ga[k].defined());
        CHECK(max_abs(ga[k]) > 0);
        CHECK(torch::equal(ga[k], gb[k]));
      }
    }
  }
}

TEST_CASE("render: a colour-only loss without the depth map gets the same images and gradients", "[render]") {
  // The recipe trains on colour alone: the forward leaves the depth out (depth_map = false) and, with no gradient
  // on depth or alpha, the backward's pixel loops leave their terms out. Against the full pass, whose loss adds
  // zero-weighted depth and alpha terms (so their gradients are zeros, not absent), everything else is equal.
  for (auto dtype : {torch::kFloat32, torch::kFloat64}) {
    for (splat::Simd level : simd_levels()) {
      CAPTURE(dtype, splat::simd_name(level));
      const splat::Simd before = splat::set_simd_level(level);
      const Camera cam = make_camera(96, 80, 80.0, 80.0, 0.3, true, dtype);
      const Gaussians scene = random_scene(800, cam, 23).to(dtype);
      const Weights w = random_weights(80, 96, 24, dtype);
      RenderMaps maps;
      maps.normals = false;
      RenderMaps lean_maps = maps;
      lean_maps.depth_map = false;
      const Gaussians a = with_grad(scene), b = with_grad(scene);
      const RenderOutput full = render(a, cam, {}, maps), lean = render(b, cam, {}, lean_maps);
      ((full.rgb * w.rgb).sum() + 0.0 * full.depth.sum() + 0.0 * full.alpha.sum()).backward();
      (lean.rgb * w.rgb).sum().backward();
      splat::set_simd_level(before);
      CHECK(full.depth.sizes() == torch::IntArrayRef({1, 80, 96}));
      CHECK(lean.depth.numel() == 0);
      CHECK(torch::equal(full.rgb, lean.rgb));
      CHECK(torch::equal(full.alpha, lean.alpha));
      CHECK(max_abs(full.alpha) > 0.5);
      const auto ga = grads_of(a), gb = grads_of(b);
      for (size_t k = 0; k < ga.size(); ++k) {
        CAPTURE(kNames[k]);
        REQUIRE(ga[k].defined());
        REQUIRE(gb[k].defined());
        CHECK(max_abs(ga[k]) > 0);
        CHECK(torch::equal(ga[k], gb[k]));
      }
    }
  }
}
namespace {
// Flat, opaque Gaussians tiling the slanted plane z = 3 + 0.6·y (camera space) every 1.5 px, seen by `cam`.
Gaussians slanted_plane(const Camera& cam) {
  std::vector<double> uv;
  for (double v = -4; v < cam.height + 4; v += 1.5)
    for (double u = -4; u < cam.width + 4; u += 1.5) uv.insert(uv.end(), {u, v});
  const int64_t n = int64_t(uv.size() / 2);
  const Tensor rays = backproject_points(torch::tensor(uv, kF64).reshape({n, 2}), torch::ones({n}, kF64),
                                         cam.K.to(kF64));  // (a, b, 1)
  const Tensor z = 3.0 / (1.0 - 0.6 * rays.select(1, 1));
  // World rotation whose third column is the plane's normal: the shortest axis.
  const Tensor R_cw = cam.T_cw.to(kF64).slice(0, 0, 3).slice(1, 0, 3);
  Eigen::Vector3d n_cam(0.0, -0.6, 1.0), t1_cam(1.0, 0.0, 0.0);
  n_cam.normalize();
  Eigen::Matrix3d R_cam;
  R_cam.col(0) = t1_cam, R_cam.col(1) = n_cam.cross(t1_cam), R_cam.col(2) = n_cam;
  Eigen::Matrix3d Rcw;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Rcw(r, c) = R_cw[r][c].item<double>();
  const Eigen::Vector4d q = quaternion_from_rotation(Rcw.transpose() * R_cam);
  const double f = cam.K[0][0].item<double>();
  Gaussians g;
  g.means = to_world(rays * z.unsqueeze(1), cam);
  g.scales = torch::stack({z * 1.2 / f, z * 1.2 / f, z * 1e-4}, 1);
  g.quats = torch::tensor({q[0], q[1], q[2], q[3]}, kF64).repeat({n, 1});
  g.colors = torch::full({n, 3}, 0.5, kF64);
  g.opacities = torch::full({n}, 0.95, kF64);
  return g;
}
}  // namespace

TEST_CASE("render: plane depth follows a slanted surface that mean depths leave in steps", "[render]") {
  const Camera cam = make_camera(96, 72, 80.0, 80.0, 0.3, true);
  const Gaussians g = slanted_plane(cam);
  const Tensor b = (torch::arange(72, kF64).unsqueeze(1) + 0.5 - cam.K[1][2]) / cam.K[1][1];
  const Tensor truth = (3.0 / (1.0 - 0.6 * b)).expand({72, 96});
  auto relative_error = [&](const RenderOutput& o) {
    const Tensor a = o.alpha[0], ok = a > 0.99;
    REQUIRE(ok.sum().item<int64_t>() > 72 * 96 * 9 / 10);
    return ((o.depth[0] / a - truth).abs() / truth).masked_select(ok);
  };
  RenderOptions plane;
  plane.depth = "plane";
  const Tensor e_center = relative_error(render(g, cam)), e_plane = relative_error(render(g, cam, plane));
  CHECK(e_plane.max().item<double>() < 1e-9);  // exact on a plane, up to rounding
  CHECK(e_plane.mean().item<double>() < e_center.mean().item<double>() / 5);
  CHECK(render(g, cam, plane).rgb.equal(render(g, cam).rgb));  // colour does not depend on the depth mode
}

TEST_CASE("render: median depth is the surface a pixel shows, not the blend of what it sees", "[render]") {
  const Camera cam = centred_camera(48, 32, 100.0);
  RenderMaps median;
  median.median_depth = true;
  // A half-transparent near Gaussian (z = 2, opacity 0.6, σ = 2 px) over an opaque far one (z = 4, σ = 5 px).
  const Gaussians g = head_on(
      {{0.0, 0.0, 2.0, 0.04, 0.04, 0.04, 0.6, 1.0, 0.0, 0.0}, {0.0, 0.0, 4.0, 0.2, 0.2, 0.2, 1.0, 0.0, 1.0, 0.0}});
  const RenderOutput out = render(g, cam, {}, median);
  REQUIRE(out.median_depth.sizes() == torch::IntArrayRef({1, 32, 48}));
  // Centre: T = 0.4 after the near one, so it shows z = 2; the mean depth blends 0.6·2 + 0.4·0.99·4.
  CHECK(out.median_depth[0][16][24].item<double>() == 2.0);
  CHECK(out.depth[0][16][24].item<double>() / out.alpha[0][16][24].item<double>() > 2.5);
  // 2 px off the near one's centre its α is 0.6·e^(−4/(2·4.3)) < 0.5: the pixel shows the far surface.
  CHECK(out.median_depth[0][16][26].item<double>() == 4.0);
  // Beyond the far one's reach nothing is drawn (alpha < 0.5): 0.
  CHECK(out.median_depth[0][16][45].item<double>() == 0.0);
  CHECK(out.alpha[0][16][45].item<double>() < 0.5);
  // Without the option there is none, and asking for it changes nothing else.
  const RenderOutput plain = render(g, cam);
  CHECK_FALSE(plain.median_depth.defined());
  CHECK(plain.rgb.equal(out.rgb));
  CHECK(plain.depth.equal(out.depth));

  // Random scenes: the dense reference's first composited Gaussian that leaves T at 0.5 or below, in float64 and
  // float32, with 1 and 2 threads; every pixel with alpha >= 0.5 has one, every other pixel none.
  const Camera wide = make_camera(70, 45, 55.0, 58.0, 0.8, true);
  const Gaussians scene = concat({random_scene(300, wide, 7), random_scene(60, wide, 9, 0.3, 3.0, 8.0, 0.9, 1.0)});
  const RenderOutput ref = test::reference_render(scene, wide, {}, median);
  const RenderOutput ours = render(scene, wide, {}, median);
  CHECK(max_abs(ours.median_depth - ref.median_depth) < 1e-12);
  CHECK(torch::equal(ours.median_depth > 0, ours.alpha >= 0.5));
  CHECK((ours.median_depth > 0).sum().item<int64_t>() > 45 * 70 / 4);
  const RenderOutput f32 = render(scene.to(torch::kFloat32), wide.to(torch::kFloat32), {}, median);
  // Float rounding may move a crossing that sits on 0.5 to the next Gaussian: at most a handful of pixels.
  CHECK(((f32.median_depth.to(kF64) - ref.median_depth).abs() > 1e-4).sum().item<int64_t>() <= 45 * 70 / 200);
  CHECK(torch::equal(f32.median_depth > 0,
                     f32.alpha >= 0.5f));  // the probe's float loop crosses where the SIMD's alpha does
  // Every SIMD level's probe gives the portable loop's depths bit for bit (AVX-512 has its own), mean and plane.
  for (const std::string depth : {"center", "plane"}) {
    RenderOptions o;
    o.depth = depth;
    std::vector<Tensor> medians;
    for (splat::Simd level : simd_levels()) {
      const splat::Simd before = splat::set_simd_level(level);
      medians.push_back(render(scene.to(torch::kFloat32), wide.to(torch::kFloat32), o, median).median_depth);
      splat::set_simd_level(before);
    }
    for (size_t k = 1; k < medians.size(); ++k) {
      CAPTURE(depth, k);
      CHECK(torch::equal(medians[0], medians[k]));
    }
  }
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const Tensor one = render(scene, wide, {}, median).median_depth;
  at::set_num_threads(2);
  CHECK(torch::equal(one, render(scene, wide, {}, median).median_depth));
  at::set_num_threads(threads);
  // Plane depth: on a slanted plane the median is the plane's depth along each pixel's ray, as the mean is.
  const Camera slant = make_camera(96, 72, 80.0, 80.0, 0.3, true);
  RenderOptions plane;
  plane.depth = "plane";
  const RenderOutput sp = render(slanted_plane(slant), slant, plane, median);
  const Tensor opaque = sp.alpha > 0.99;
  REQUIRE(opaque.sum().item<int64_t>() > 72 * 96 * 9 / 10);
  CHECK(max_abs((sp.median_depth - sp.depth / sp.alpha) * opaque) < 1e-9);
  // Batched: one per camera.
  const RenderOutput two = render(g, stack_cameras({cam, cam}), {}, median);
  CHECK(two.median_depth.sizes() == torch::IntArrayRef({2, 1, 32, 48}));
  CHECK(torch::equal(two.median_depth[1], out.median_depth));
}

TEST_CASE("render: plane depth has no gradient and leaves the other gradients alone", "[render]") {
  const Camera cam = make_camera(96, 80, 80.0, 80.0, 0.3, true, torch::kFloat32);
  const Gaussians scene = random_scene(600, cam, 31).to(torch::kFloat32);
  Weights w = random_weights(80, 96, 32, torch::kFloat32);
  RenderOptions plane;
  plane.depth = "plane";
  const Gaussians a = with_grad(scene);
  const RenderOutput out = render(a, cam, plane);
  CHECK_FALSE(out.depth.requires_grad());
  weighted_loss(out, w).backward();  // the depth term adds nothing
  w.depth = torch::zeros_like(w.depth);
  const auto center = outputs_and_grads(scene, cam, w);
  const auto grads = grads_of(a);
  for (size_t k = 0; k < grads.size(); ++k) {
    CAPTURE(kNames[k]);
    CHECK(torch::equal(grads[k], center[4 + k]));
  }
  plane.depth = "middle";
  CHECK_THROWS_WITH(render(scene, cam, plane), Catch::Contains("center or plane"));
}

namespace {
// Each Gaussian's largest weight α·T over the pixels, from the dense reference: weights do not depend on
// colours, so three Gaussians at a time get one-hot colours and the rendered channels are their weights.
Tensor reference_max_weight(const Gaussians& g, const Camera& cam) {
  const int64_t n = g.count();
  Tensor out = torch::zeros({n}, kF64);
  for (int64_t i0 = 0; i0 < n; i0 += 3) {
    Gaussians probe = g;
    probe.colors = torch::zeros({n, 3}, kF64);
    for (int64_t c = 0; c < 3 && i0 + c < n; ++c) probe.colors[i0 + c][c] = 1.0;
    const Tensor rgb = test::reference_render(probe, cam, RenderOptions{}).rgb;
    for (int64_t c = 0; c < 3 && i0 + c < n; ++c) out[i0 + c] = rgb[c].max();
  }
  return out;
}
}  // namespace

TEST_CASE("prune: the contribution measure equals the dense reference's largest weight per Gaussian", "[render]") {
  const Camera cam = make_camera(40, 28, 36.0, 36.0, 0.2, true);
  const Gaussians scene = random_scene(45, cam, 31, 1.6);
  const Tensor ours = max_contribution(scene, cam), ref = reference_max_weight(scene, cam);
  CHECK(max_abs(ours - ref) < 1e-9);
  CHECK((ref > 0.05).sum().item<int64_t>() > 10);  // many contribute
  CHECK((ref == 0).sum().item<int64_t>() > 0);     // and some (outside the frustum or occluded) do not
  // Float precision agrees with the double-precision measure.
  CHECK(max_abs(max_contribution(scene.to(torch::kFloat32), cam.to(torch::kFloat32)).to(kF64) - ref) < 1e-4);
  // Every SIMD level's probe gives the portable loop's weights bit for bit (AVX-512 has its own), on a scene large
  // enough for whole-row and paired jobs and for tiles that fill up.
  const Camera wide = make_camera(90, 60, 70.0, 70.0, 0.3, true, torch::kFloat32);
  const Gaussians many =
      concat({random_scene(500, wide, 33), random_scene(80, wide, 34, 0.3, 3.0, 8.0, 0.9, 1.0)}).to(torch::kFloat32);
  std::vector<Tensor> weights;
  for (splat::Simd level : simd_levels()) {
    const splat::Simd before = splat::set_simd_level(level);
    weights.push_back(max_contribution(many, wide));
    splat::set_simd_level(before);
  }
  CHECK((weights[0] > 0.05f).sum().item<int64_t>() > 100);
  for (size_t k = 1; k < weights.size(); ++k) {
    CAPTURE(k);
    CHECK(torch::equal(weights[0], weights[k]));
  }
}

TEST_CASE("prune: never removes a Gaussian that contributes at least the threshold in any view", "[render]") {
  const Camera cam = make_camera(40, 28, 36.0, 36.0, 0.0, true);
  const Gaussians scene = random_scene(60, cam, 33, 1.3);
  PruneOptions o;
  o.enabled = true;
  o.min_opacity = 0.1;
  o.min_contribution = 0.05;
  o.views = 2;
  o.view_shift = 0.15;
  const PruneResult r = prune_gaussians(scene, cam, o);
  // The same views, measured with the dense reference.
  const auto T = cam.T_cw.to(kF64);
  const double median_z = (torch::matmul(scene.means, T.index({2, torch::indexing::Slice(0, 3)})) + T.index({2, 3}))
                              .median()
                              .item<double>();
  Tensor best = reference_max_weight(scene, cam);
  for (const Camera& v : nearby_views(cam, o.view_shift * median_z, o.views))
    best = torch::maximum(best, reference_max_weight(scene, v));
  const Tensor expected = (scene.opacities >= o.min_opacity).logical_and(best >= o.min_contribution);
  CHECK(torch::equal(r.keep, expected));
  CHECK(r.low_opacity == (scene.opacities < o.min_opacity).sum().item<int64_t>());
  CHECK(r.after() == r.kept.count());
  CHECK(r.low_contribution > 0);
  CHECK(r.after() < r.before);
  // Disabled keeps everything.
  o.enabled = false;
  CHECK(prune_gaussians(scene, cam, o).kept.count() == scene.count());
}

TEST_CASE("prune: virtual views move the camera centre along its own axes", "[render]") {
  const Camera cam = make_camera(32, 24, 30.0, 30.0, 0.0, true);
  auto centre = [](const Camera& c) {
    const Tensor T = c.T_cw.to(kF64);
    const Tensor R = T.slice(0, 0, 3).slice(1, 0, 3), t = T.slice(0, 0, 3).select(1, 3);
    return -torch::matmul(R.t(), t);
  };
  const auto views = nearby_views(cam, 0.5, 6);
  REQUIRE(views.size() == 6);
  const Tensor R = cam.T_cw.to(kF64).slice(0, 0, 3).slice(1, 0, 3);
  for (int64_t k = 0; k < 6; ++k) {
    const Tensor moved = centre(views[size_t(k)]) - centre(cam);
    const Tensor axis = R[k / 2] * (k % 2 == 0 ? 0.5 : -0.5);  // row a of R is camera axis a in world
    CHECK(max_abs(moved - axis) < 1e-12);
  }
  CHECK_THROWS_AS(nearby_views(cam, 0.5, 7), Error);
}

namespace {
// The covariance R diag(s²) Rᵀ of Gaussian i.
Eigen::Matrix3d covariance_of(const Gaussians& g, int64_t i) {
  const Tensor q = g.quats[i].to(kF64), s = g.scales[i].to(kF64);
  const Eigen::Matrix3d R = rotation_from_quaternion(
      Eigen::Vector4d(q[0].item<double>(), q[1].item<double>(), q[2].item<double>(), q[3].item<double>()));
  const Eigen::Vector3d s2(s[0].item<double>(), s[1].item<double>(), s[2].item<double>());
  return R * s2.cwiseProduct(s2).asDiagonal() * R.transpose();
}

// A fronto-parallel plane at depth z with one Gaussian per pixel centre of `cam` (centred_camera), in-plane σ
// of 0.6 px; colours uniform, or a per-pixel checkerboard when `textured`.
Gaussians pixel_plane(const Camera& cam, double z, bool textured) {
  const double f = cam.K[0][0].item<double>(), px = z / f;
  std::vector<std::array<double, 10>> rows;
  for (int64_t i = 0; i < cam.height; ++i)
    for (int64_t j = 0; j < cam.width; ++j) {
      const double x = (double(j) - 0.5 * double(cam.width)) * px, y = (double(i) - 0.5 * double(cam.height)) * px;
      const double c = textured && (i + j) % 2 ? 0.8 : 0.3;
      rows.push_back({x, y, z, 0.6 * px, 0.6 * px, 0.002, 0.95, c, c, c});
    }
  return head_on(rows);
}
}  // namespace

TEST_CASE("merge: a flat single-coloured cell becomes one Gaussian with its members' moments", "[render]") {
  const Camera cam = centred_camera(48, 32, 20.0);  // u = 20 x / z + 24.5 px, v = 20 y / z + 16.5 px
  // Four members at (0.2 ± 0.05, 0.1 ± 0.05, 2): pixels 27.5–29.5 and 17.5–19.5, one 8-px cell.
  std::vector<std::array<double, 10>> rows;
  for (double dx : {-0.05, 0.05})
    for (double dy : {-0.05, 0.05})
      rows.push_back({0.2 + dx, 0.1 + dy, 2.0, 0.02, 0.03, 0.001, 0.9, 0.3, 0.5, 0.7 + 0.01 * dx / 0.05});
  const Gaussians cell = head_on(rows);
  MergeOptions o;
  o.cell_px = 8;
  const MergeResult r = merge_gaussians(cell, cam, o);
  REQUIRE(r.merged.count() == 1);
  CHECK(r.groups == 1);
  CHECK(r.members == 4);
  CHECK(r.removed() == 3);
  CHECK(max_abs(r.merged.means[0] - torch::tensor({0.2, 0.1, 2.0}, kF64)) < 1e-12);
  CHECK(max_abs(r.merged.colors[0] - torch::tensor({0.3, 0.5, 0.7}, kF64)) < 1e-12);
  CHECK(r.merged.opacities[0].item<double>() == Approx(0.9));
  // Members' covariance plus the spread of their means; here the members do not tile the cell (their area,
  // 4 x 0.02 x 0.03, is below the moment-matched area), so nothing grows.
  const Eigen::Matrix3d expected = Eigen::Vector3d(0.02 * 0.02 + 0.0025, 0.03 * 0.03 + 0.0025, 1e-6).asDiagonal();
  CHECK((covariance_of(r.merged, 0) - expected).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(r.merged.opacities.dim() == 1);
  // Off: the set is returned as it is.
  CHECK(merge_gaussians(cell, cam, MergeOptions{}).merged.means.is_same(cell.means));
}

TEST_CASE("merge: other colours, a depth edge and Gaussians behind the camera stay apart", "[render]") {
  const Camera cam = centred_camera(48, 32, 20.0);
  MergeOptions o;
  o.cell_px = 8;
  o.max_color = 0.03;
  // Two members side by side; the second at depth z2 (same pixel cell) with thickness t.
  auto pair = [](double z2, double colour2, double t = 0.001) {
    return head_on({{0.2, 0.1, 2.0, 0.02, 0.02, t, 0.9, 0.5, 0.5, 0.5},
                    {0.25 * z2 / 2, 0.1 * z2 / 2, z2, 0.02, 0.02, t, 0.9, colour2, 0.5, 0.5}});
  };
  CHECK(merge_gaussians(pair(2.0, 0.54), cam, o).merged.count() == 1);  // within 0.03 of the mean 0.52
  CHECK(merge_gaussians(pair(2.0, 0.58), cam, o).merged.count() == 2);  // 0.04 from the mean
  // 0.5 m apart in depth. Flat members: their normals (z) cross the merged plane, which holds the depth step.
  CHECK(merge_gaussians(pair(2.5, 0.5), cam, o).merged.count() == 2);
  // Round members have no normal, but the pair is as thick as it is narrow: not flat.
  CHECK(merge_gaussians(pair(2.5, 0.5, 0.02), cam, o).merged.count() == 2);
  o.max_flatness = 1.0;
  CHECK(merge_gaussians(pair(2.5, 0.5, 0.02), cam, o).merged.count() == 1);
  CHECK(merge_gaussians(pair(2.5, 0.5), cam, o).merged.count() == 2);
  o.min_normal_cos = 0.0;
  CHECK(merge_gaussians(pair(2.5, 0.5), cam, o).merged.count() == 1);  // any shape allowed
  const Gaussians behind = head_on({{0.2, 0.1, -2.0, 0.02, 0.02, 0.001, 0.9, 0.5, 0.5, 0.5},
                                    {0.2, 0.1, -2.0, 0.02, 0.02, 0.001, 0.9, 0.5, 0.5, 0.5}});
  CHECK(merge_gaussians(behind, cam, o).merged.count() == 2);
  CHECK(merge_gaussians(behind, cam, o).alone == 2);  // behind the camera: no cell, nothing to merge with
  CHECK(merge_gaussians(pair(2.0, 0.58), cam, o).alone == 0);
  // Two members in 4-px cells of their own (u 26.5 and 30.5 px: cells 6 and 7) are alone; in 8-px cells they merge.
  const Gaussians apart = head_on(
      {{0.2, 0.1, 2.0, 0.02, 0.02, 0.001, 0.9, 0.5, 0.5, 0.5}, {0.6, 0.1, 2.0, 0.02, 0.02, 0.001, 0.9, 0.5, 0.5, 0.5}});
  o.cell_px = 4;
  const MergeResult two = merge_gaussians(apart, cam, o);
  CHECK(two.alone == 2);
  CHECK(two.groups == 0);
  o.cell_px = 8;
  CHECK(merge_gaussians(apart, cam, o).groups == 1);
}

TEST_CASE("merge: a split cell merges its single-coloured part and keeps the odd member", "[render]") {
  const Camera cam = centred_camera(48, 32, 20.0);
  // One 8-px cell: three grey members and one red one, all on the plane z = 2.
  std::vector<std::array<double, 10>> rows;
  for (double dx : {-0.05, 0.05})
    for (double dy : {-0.05, 0.05}) {
      const bool odd = dx > 0 && dy > 0;
      rows.push_back({0.2 + dx, 0.1 + dy, 2.0, 0.02, 0.02, 0.001, 0.9, odd ? 0.9 : 0.5, 0.5, 0.5});
    }
  const Gaussians cell = head_on(rows);
  MergeOptions o;
  o.cell_px = 8;
  const MergeResult whole = merge_gaussians(cell, cam, o);
  CHECK(whole.merged.count() == 4);
  CHECK(whole.refused_color == 1);
  o.split = true;
  const MergeResult split = merge_gaussians(cell, cam, o);
  REQUIRE(split.merged.count() == 2);
  CHECK(split.groups == 1);
  CHECK(split.members == 3);
  // The grey three merge into one grey Gaussian at their mean; the red one is kept as it was.
  const Tensor red = split.merged.colors.select(1, 0) > 0.7;
  REQUIRE(red.sum().item<int64_t>() == 1);
  CHECK(max_abs(split.merged.colors.index({red.logical_not()}) - torch::tensor({{0.5, 0.5, 0.5}}, kF64)) < 1e-12);
  CHECK(max_abs(split.merged.means.index({red}) - torch::tensor({{0.25, 0.15, 2.0}}, kF64)) < 1e-12);
  CHECK(max_abs(split.merged.means.index({red.logical_not()}) -
                torch::tensor({{0.2 - 0.05 / 3, 0.1 - 0.05 / 3, 2.0}}, kF64)) < 1e-12);
  // A cell of one colour refused for its shape is not split: the depth step stays apart.
  std::vector<std::array<double, 10>> step = rows;
  for (auto& row : step) row[7] = 0.5;
  step[3][2] = 2.5, step[3][0] *= 1.25, step[3][1] *= 1.25;
  const MergeResult kept = merge_gaussians(head_on(step), cam, o);
  CHECK(kept.merged.count() == 4);
  CHECK(kept.refused_color == 0);
  CHECK(kept.refused_shape + kept.refused_normal == 1);  // tried once, whole
  // With a red member too, the cell is refused by colour, then its grey part for the depth step: both counted.
  step[2][7] = 0.9;
  const MergeResult parts = merge_gaussians(head_on(step), cam, o);
  CHECK(parts.merged.count() == 4);
  CHECK(parts.refused_color == 1);
  CHECK(parts.refused_shape + parts.refused_normal == 1);
}

TEST_CASE("merge: a plain plane keeps a quarter of its Gaussians and renders the same, a textured one keeps all",
          "[render]") {
  const Camera cam = centred_camera(48, 32, 40.0);
  MergeOptions o;
  o.cell_px = 2;
  const Gaussians plain = pixel_plane(cam, 2.0, false), textured = pixel_plane(cam, 2.0, true);
  const MergeResult merged = merge_gaussians(plain, cam, o);
  CHECK(merged.merged.count() == plain.count() / 4);
  CHECK(merge_gaussians(textured, cam, o).merged.count() == textured.count());
  // The grown footprints keep the plane closed: inside a 3-px border, colour and alpha stay within a few
  // hundredths of the unmerged plane's (moment matching alone leaves alpha near 0.86 at pixel centres).
  const auto inner = [](const Tensor& t, int64_t border = 3) {
    return t.slice(1, border, -border).slice(2, border, -border);
  };
  const RenderOutput before = render(plain, cam), after = render(merged.merged, cam);
  CHECK(max_abs(inner(after.rgb - before.rgb)) < 0.03);
  CHECK(inner(after.alpha).min().item<double>() > 0.9);
  // The same plane seen from a view 4 px to the side renders the same too.
  const Camera moved = nearby_views(cam, 0.2, 2)[0];
  CHECK(max_abs(inner(render(merged.merged, moved).rgb - render(plain, moved).rgb, 7)) < 0.03);
  // Through prune_gaussians, merging follows the drops and is counted.
  PruneOptions po;
  po.enabled = true;
  po.min_contribution = 0;
  po.merge = o;
  const PruneResult pr = prune_gaussians(plain, cam, po);
  CHECK(pr.merge.removed() == plain.count() - plain.count() / 4);
  CHECK(pr.after() == pr.kept.count());
}

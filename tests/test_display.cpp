// Display resolution: upscaled cameras see the same view, and the hole share at k times the working size finds the
// gaps between Gaussians that are smaller than their share of the surface.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "core/error.h"
#include "core/runtime.h"
#include "metrics/display.h"
#include "render/render.h"

using namespace isplat;

namespace display_test {

// A W x H camera at the origin looking down +z, focal f, principal point at the image centre.
Camera camera(int64_t W, int64_t H, double f) {
  auto K = torch::tensor({f, 0.0, 0.5 * W, 0.0, f, 0.5 * H, 0.0, 0.0, 1.0}, torch::kFloat64).reshape({3, 3});
  return Camera{K, torch::eye(4, torch::kFloat64), W, H};
}

// One flat, head-on Gaussian per pixel centre of `cam` on the plane z = 2, each `footprint` pixels wide (std).
Gaussians pixel_plane(const Camera& cam, double footprint) {
  const double f = cam.K[0][0].item<double>(), z = 2.0;
  const int64_t W = cam.width, H = cam.height, N = W * H;
  auto j = torch::arange(W, torch::kFloat64).repeat({H}), i = torch::arange(H, torch::kFloat64).repeat_interleave(W);
  const auto x = (j + 0.5 - 0.5 * W) * z / f, y = (i + 0.5 - 0.5 * H) * z / f;
  const double s = footprint * z / f;
  return {torch::stack({x, y, torch::full({N}, z, torch::kFloat64)}, 1),
          torch::tensor({s, s, 0.01 * s}, torch::kFloat64).repeat({N, 1}),
          torch::tensor({1.0, 0.0, 0.0, 0.0}, torch::kFloat64).repeat({N, 1}),
          torch::full({N, 3}, 0.5, torch::kFloat64), torch::full({N}, 0.95, torch::kFloat64)};
}

// The test cases live in the namespace too: a using-directive would leak its names into the next file of a
// unity batch.

TEST_CASE("display: an upscaled camera sees the same view at k times the size", "[metrics][display]") {
  const Camera cam = camera(40, 30, 50.0);
  const Camera big = upscaled_camera(cam, 4.0);
  CHECK(big.width == 160);
  CHECK(big.height == 120);
  CHECK(torch::allclose(
      big.K, torch::tensor({200.0, 0.0, 80.0, 0.0, 200.0, 60.0, 0.0, 0.0, 1.0}, torch::kFloat64).reshape({3, 3})));
  CHECK(torch::equal(big.T_cw, cam.T_cw));
  CHECK(torch::equal(cam.K[0][0], torch::tensor(50.0, torch::kFloat64)));  // the input is untouched
  // A Gaussian's image moves with the image: its centre lands on the same relative spot.
  const Gaussians one = pixel_plane(camera(1, 1, 50.0), 3.0);
  const RenderOutput small_out = render(one, cam), big_out = render(one, big);
  CHECK(small_out.alpha[0][15][20].item<double>() > 0.9);
  CHECK(big_out.alpha[0][60][80].item<double>() > 0.9);
  CHECK_THROWS_WITH(upscaled_camera(cam, 0.5), Catch::Contains("factor 0.5"));
  const int64_t limit = max_image_pixels();
  CHECK_THROWS_WITH(upscaled_camera(cam, std::sqrt(static_cast<double>(limit)) / 10.0),
                    Catch::Contains("runtime.max_image_pixels"));
}

TEST_CASE("display: the central hole share counts alpha below 0.5 in the centre only", "[metrics][display]") {
  auto alpha = torch::ones({1, 10, 20}, torch::kFloat64);
  alpha.narrow(1, 0, 1).fill_(0.0);  // the top row lies outside the central 80%
  CHECK(central_hole_share(alpha) == 0.0);
  alpha[0][5][10] = 0.49;
  alpha[0][5][11] = 0.5;  // not a hole
  CHECK(central_hole_share(alpha) == Approx(1.0 / (8 * 16)));
  CHECK(central_hole_share(alpha, 1.0) == Approx(21.0 / 200));
  CHECK_THROWS_WITH(central_hole_share(alpha, 0.0), Catch::Contains("central 0"));
  CHECK_THROWS_WITH(central_hole_share(torch::ones({2, 3, 4})), Catch::Contains("[1,H,W] or [H,W]"));
}

TEST_CASE("display: Gaussians smaller than their pixel leave gaps at 4x that the working size hides",
          "[metrics][display]") {
  const Camera cam = camera(32, 24, 40.0);
  const Gaussians thin = pixel_plane(cam, 0.15), wide = pixel_plane(cam, 0.6);
  // At the working size the renderer's 0.3 px^2 dilation closes both planes ...
  CHECK(upscaled_hole_share(thin, cam, 1.0, RenderOptions{}) == 0.0);
  CHECK(upscaled_hole_share(wide, cam, 1.0, RenderOptions{}) == 0.0);
  // ... at 4x the dilation is a sixteenth of a working pixel: the thin plane opens, the wide one stays closed.
  const double thin4 = upscaled_hole_share(thin, cam, 4.0, RenderOptions{});
  CHECK(thin4 > 0.5);
  CHECK(upscaled_hole_share(wide, cam, 4.0, RenderOptions{}) == 0.0);
  CHECK(upscaled_hole_share(thin, cam, 2.0, RenderOptions{}) < thin4);
}

}  // namespace display_test

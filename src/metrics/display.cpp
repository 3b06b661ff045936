// Scenes seen above their working size: upscaled cameras and the holes they show.
#include "metrics/display.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "core/runtime.h"

namespace isplat {

Camera upscaled_camera(const Camera& camera, double factor) {
  ISPLAT_CHECK(std::isfinite(factor) && factor >= 1.0, "upscaled camera: factor ", factor, " must be at least 1");
  Camera out = camera;
  out.width = static_cast<int64_t>(std::lround(camera.width * factor));
  out.height = static_cast<int64_t>(std::lround(camera.height * factor));
  ISPLAT_CHECK(out.width <= max_image_pixels() / std::max<int64_t>(out.height, 1), "upscaled camera: ", out.width, "x",
               out.height, " (", factor, " x ", camera.width, "x", camera.height,
               ") is above runtime.max_image_pixels = ", max_image_pixels());
  // Scale by the rounded size, so the image edges 0 and W still map to 0 and W'.
  const double sx = static_cast<double>(out.width) / camera.width, sy = static_cast<double>(out.height) / camera.height;
  auto K = camera.K.clone();
  K.select(-2, 0).mul_(sx);
  K.select(-2, 1).mul_(sy);
  out.K = K;
  return out;
}

double central_hole_share(const torch::Tensor& alpha, double central, double hole_alpha) {
  ISPLAT_CHECK(central > 0 && central <= 1, "central hole share: central ", central, " must be in (0, 1]");
  ISPLAT_CHECK(alpha.dim() == 2 || (alpha.dim() == 3 && alpha.size(0) == 1),
               "central hole share: alpha must be [1,H,W] or [H,W], got ", alpha.sizes());
  const auto a = alpha.dim() == 3 ? alpha.select(0, 0) : alpha;
  const int64_t H = a.size(0), W = a.size(1);
  const int64_t h = std::max<int64_t>(1, std::lround(H * central)), w = std::max<int64_t>(1, std::lround(W * central));
  const auto inner = a.narrow(0, (H - h) / 2, h).narrow(1, (W - w) / 2, w);
  return (inner < hole_alpha).to(torch::kFloat64).mean().item<double>();
}

double upscaled_hole_share(const Gaussians& gaussians, const Camera& camera, double factor,
                           const RenderOptions& options, double central) {
  const RenderOutput out = render(gaussians, upscaled_camera(camera, factor), options, RenderMaps::colour_only());
  return central_hole_share(out.alpha, central);
}

}  // namespace isplat

// Scenes seen above their working size: cameras scaled up, and the holes a viewer at display resolution sees.
#pragma once
#include <torch/types.h>

#include "core/gaussians.h"
#include "geometry/camera_torch.h"
#include "render/render.h"

namespace isplat {

// The same camera with an image `factor` times as wide and tall (continuous coordinates scale with the image, so the
// view is the same): K's first two rows times factor. factor >= 1; the size rounds to whole pixels.
Camera upscaled_camera(const Camera& camera, double factor);

// Share of the central `central` fraction (per axis) of an unbatched render's pixels whose alpha ([1,H,W] or [H,W])
// is below hole_alpha: what a viewer sees of the background through gaps in the surface.
double central_hole_share(const torch::Tensor& alpha, double central = 0.8, double hole_alpha = 0.5);

// Renders `gaussians` from `camera` at `factor` times its size (colour and alpha only) and returns the central hole
// share. Fails naming the size when the upscaled image would exceed runtime.max_image_pixels.
double upscaled_hole_share(const Gaussians& gaussians, const Camera& camera, double factor,
                           const RenderOptions& options, double central = 0.8);

}  // namespace isplat

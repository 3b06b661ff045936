// Scale alignment of a prediction to a capture whose units are not metres (scoring.align_scale, predict
// --align-points): the median ratio of reference to rendered depth at reference samples, applied about the camera.
#pragma once
#include <cstdint>

#include "core/gaussians.h"
#include "geometry/camera_torch.h"
#include "render/render.h"

namespace isplat {

struct ScaleFit {
  double factor = 1.0;  // multiplies camera-space positions and scales; 1 when no sample was usable
  int64_t samples = 0;  // reference samples where the prediction shows a surface (0 = not aligned)
};

// Reference samples from a dense depth map [H,W] (valid [H,W]): (u, v, z) at every valid pixel centre, [P,3].
torch::Tensor depth_samples(const torch::Tensor& depth, const torch::Tensor& valid);

// The factor that brings `scene` (world frame) to the reference: the median over `samples` [P,3] (u, v, z: pixel
// coordinates of `camera` and reference planar depth in the capture's units) of z / the rendered depth at that pixel.
// The rendered depth is the median depth (the surface the pixel shows); pixels with alpha < 0.5 are skipped.
ScaleFit fit_scene_scale(const Gaussians& scene, const Camera& camera, const torch::Tensor& samples,
                         const RenderOptions& options = {});

// `scene` with camera-space positions and scales multiplied by `factor` about `camera`'s centre (rotations,
// colours and opacities unchanged): how a scene seen from `camera` looks the same at another scale.
Gaussians scale_about_camera(const Gaussians& scene, const Camera& camera, double factor);

}  // namespace isplat

// GaussianComposer: base Gaussians + bounded 14-dim updates -> metric Gaussians (DESIGN §3, release).
#pragma once
#include <torch/types.h>

#include <string>

#include "core/gaussians.h"
#include "sampler/base_gaussians.h"

namespace isplat {

class ConfigVisitor;

// Delta layout: du, dv, dz, ds(3), dq(4, wxyz), dc(3), dalpha.
constexpr int64_t kDeltaDim = 14;

struct ComposerOptions {
  double lambda_xy = 0.77;  // pixels per unit du/dv (release: 1e-3 NDC at 1536 px)
  double lambda_z = 1e-3;   // inverse-depth step per unit dz
  double color_step = 0.1;  // logit colour step per unit dc
  double scale_min = 0.0, scale_max = 4.0;
  bool linear_rgb = true;  // convert colours sRGB -> linear for compositing (release behaviour)
  // The frame the rotation update dq acts in: "camera" (release: the identity) or "surface" (the Gaussian's local
  // z axis starts on the support's surface normal, so a Gaussian flattened along z lies in the surface).
  std::string orientation = "camera";  // the release's; the model's default is surface (ModelOptions)
  // (scale_floor_px · z / f)² added to every axis's variance (z the depth, f the source focal length): no Gaussian
  // narrower than that share of a source pixel, so larger views see fewer gaps.
  double scale_floor_px = 0.0;  // the release's (off); the model's default is 0.35 (ModelOptions)
  void visit(ConfigVisitor& v);
};

// Gaussians in the source camera frame (metres). delta: [N,14]; K: [3,3].
Gaussians compose_camera(const BaseGaussians& base, const torch::Tensor& delta, const torch::Tensor& K,
                         const ComposerOptions& options);
// The same, moved to the world frame with the source pose T_cw [4,4].
Gaussians compose(const BaseGaussians& base, const torch::Tensor& delta, const torch::Tensor& K,
                  const torch::Tensor& T_cw, const ComposerOptions& options);
Gaussians camera_to_world(const Gaussians& g, const torch::Tensor& T_cw);

// The opacities [N] the updates give (sigmoid of dalpha, base 0.5), before compose's clamp to [0.01, 0.99].
torch::Tensor unclamped_opacity(const torch::Tensor& delta);

// The shortest-arc rotation [N,4] (wxyz) that takes the local z axis onto the line of each normal [N,3]: onto n or
// -n, whichever points away from the camera, so the arc stays under 90 degrees.
torch::Tensor quaternion_z_to_normal(const torch::Tensor& normal);

torch::Tensor inverse_softplus(const torch::Tensor& y);  // overflow-safe for large y

}  // namespace isplat

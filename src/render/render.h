// Public API of the differentiable CPU Gaussian-splatting renderer: options, maps, outputs and render().
#pragma once
#include <torch/types.h>

#include <string>
#include <vector>

#include "core/gaussians.h"
#include "geometry/camera_torch.h"

namespace isplat {

class ConfigVisitor;

struct RenderOptions {
  std::vector<double> background = {0.0, 0.0, 0.0};  // linear RGB behind the splats: rgb += T_final·bg
  bool antialiased = false;      // opacity compensation (Mip-Splatting / gsplat "antialiased") on top of the dilation
  double near = 0.01;            // metres: Gaussians with camera-space z < near are culled
  double dilation = 0.3;         // px², added to the diagonal of every 2D covariance (low-pass filter)
  std::string depth = "center";  // center: each Gaussian's mean depth (differentiable); plane: ray-plane (no gradient)
  void visit(ConfigVisitor& v);
};

// Which maps render() composites besides rgb and alpha: a per-call request, not a config key.
struct RenderMaps {
  // The normal map. Callers that never read `normal` (training) turn it off and save about a sixth of the forward
  // pass; `normal` is then an empty tensor.
  bool normals = true;
  // The depth map. Training turns it off when no loss reads `depth` (with normals off; `depth` is then an empty
  // tensor). Colour-only losses also leave the backward's depth and alpha terms out.
  bool depth_map = true;
  // median_depth: the evaluator asks for it when scoring.crack_depth = median. One more forward pass over the
  // tiles, with no gradient.
  bool median_depth = false;
  // rgb and alpha only, as training renders.
  static RenderMaps colour_only() { return {false, false, false}; }
};

// Unbatched: rgb [3,H,W], alpha [1,H,W], depth [1,H,W], normal [3,H,W] (normal and depth [0] where RenderMaps
// leaves them out); batched: a leading [B] on each.
// rgb = Σ wᵢcᵢ + T_final·bg, alpha = Σ wᵢ = 1 − T_final, depth = Σ wᵢzᵢ (not normalized by alpha), normal =
// Σ wᵢnᵢ with nᵢ the shortest axis in camera space facing the camera. zᵢ is the camera-space z of the mean
// (depth "center"), or with depth "plane" the z where the pixel's ray meets the plane through the mean normal
// to nᵢ, kept within [z/2, 2z] of the mean's z (smooth across slanted surfaces). rgb and alpha are
// differentiable, depth only in "center" mode; normal is not (it has no gradient). With maps.median_depth,
// median_depth [1,H,W] is the zᵢ of the first Gaussian after which the pixel's transmittance is 0.5 or less: the
// surface the pixel shows rather than a blend of the surfaces it sees, 0 where alpha < 0.5. It has no gradient;
// without maps.median_depth it is an undefined tensor.
struct RenderOutput {
  torch::Tensor rgb, alpha, depth, normal, median_depth;
};

// Renders Gaussians (float32 or float64, CPU) through a pinhole camera. Gradients flow to means, scales,
// quats (unnormalized), colors and opacities; none to the camera. Batching:
//   unbatched set + unbatched camera      -> [3,H,W] ...
//   unbatched set + cameras [B]           -> [B,3,H,W] ... (one set seen by B cameras)
//   sets [B,N,...] + cameras [B]          -> [B,...] (set b through camera b)
//   sets [B,N,...] + one unbatched camera -> [B,...]
// Non-finite inputs throw isplat::Error naming the tensor. Gaussians behind the near plane, with a zero
// or negative scale or opacity, a zero quaternion, a degenerate 2D covariance, too little opacity to reach
// α = 1/255, or no footprint in the image are culled (they contribute nothing and get zero gradients).
// `maps` picks the outputs beyond rgb and alpha; leaving one out changes none of the others, bit for bit.
RenderOutput render(const Gaussians& gaussians, const Camera& camera, const RenderOptions& options = {},
                    const RenderMaps& maps = {});

}  // namespace isplat
